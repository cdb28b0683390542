"""Each sentence's motion in the statistics of the training source it reads like.

Trained with ``--normalise by-source`` (``datasets.position_items.normalise_by_source``),
the two-stream model has learnt every source's motions in that source's own normalised
features: a procedural sentence's motion in the procedural corpus' means and spreads (many
body sizes), a Bandai sentence's in the Bandai takes' (one actor's body). Decoded with one
source's normaliser, every motion comes out in that source's statistics, right for its
sentences and wrong for the others'. :class:`SourceOutput` keeps every source's normaliser
and a softmax regression from the model's own sentence embedding (``TwoStreamModel.joint``
of ``encode_text``, (B, D)) to the source, so a sentence's motion is decoded with the
normaliser of the source it reads like; a sentence that reads like several is decoded with
their mix (means and spreads weighed by the probabilities). The model's outputs stay in one
space, its features' normaliser (``to_output``), so everything downstream reads them as
before.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.schema import NUMBERS, ListOf

#: at most this many sentences of each source fit the regression (drawn at random, the same
#: number from each: no source is favoured for being the bigger)
FIT_PER_SOURCE = 3000
#: a checkpoint's ``sources`` entry (:meth:`SourceOutput.to_dict`; None: one normaliser)
SCHEMA = (None, {"means": ListOf(NUMBERS), "stds": ListOf(NUMBERS),
                 "weights": ListOf(NUMBERS), "bias": NUMBERS})


@dataclass
class SourceOutput:
    """Per-source normalisers and the sentence-to-source regression.

    Attributes:
        means, stds: (S, F) each source's feature means and spreads (its own units).
        weights: (S, D) and ``bias`` (S,): softmax regression over sentence embeddings.
    """

    means: np.ndarray
    stds: np.ndarray
    weights: np.ndarray
    bias: np.ndarray

    def __post_init__(self) -> None:
        self.means, self.stds, self.weights, self.bias = (
            np.asarray(a, dtype=np.float64) for a in (self.means, self.stds, self.weights,
                                                      self.bias))
        s = len(self.means)
        if (s < 2 or self.stds.shape != self.means.shape or self.weights.ndim != 2
                or len(self.weights) != s or self.bias.shape != (s,)
                or not (self.stds > 0).all()):
            raise MotionlangError(f"source output: {s} sources need (S, F) means and positive "
                                  f"spreads, (S, D) weights and (S,) biases, got "
                                  f"{self.means.shape}, {self.stds.shape}, "
                                  f"{self.weights.shape}, {self.bias.shape}")

    @classmethod
    def fit(cls, normalizers: Sequence, z: np.ndarray, labels: Sequence[int], *,
            ridge: float = 1e-3, steps: int = 300) -> SourceOutput:
        """Fitted on sentence embeddings ``z`` (N, D) and their sources ``labels`` (N,):
        full-batch L-BFGS on the mean cross-entropy plus ``ridge`` x the squared weights."""
        y = torch.as_tensor(np.asarray(labels), dtype=torch.long)
        n = len(normalizers)
        if len(z) != len(y) or len(y) == 0 or set(y.tolist()) != set(range(n)):
            raise MotionlangError(f"source output: need sentences of each of the {n} sources, "
                                  f"got labels {sorted(set(y.tolist()))}")
        x = torch.as_tensor(np.asarray(z), dtype=torch.float64)
        w = torch.zeros(n, x.shape[1], dtype=torch.float64, requires_grad=True)
        b = torch.zeros(n, dtype=torch.float64, requires_grad=True)
        opt = torch.optim.LBFGS([w, b], max_iter=steps, line_search_fn="strong_wolfe")

        def closure():
            opt.zero_grad()
            loss = (torch.nn.functional.cross_entropy(x @ w.T + b, y)
                    + ridge * (w ** 2).sum())
            loss.backward()
            return loss

        opt.step(closure)
        return cls(np.stack([np.asarray(m.mean) for m in normalizers]),
                   np.stack([np.asarray(m.std) for m in normalizers]),
                   w.detach().numpy(), b.detach().numpy())

    def checked(self, d: int, f: int) -> SourceOutput:
        """Itself, if it reads (D = ``d``,) embeddings and normalises F = ``f`` features."""
        if self.weights.shape[1] != d or self.means.shape[1] != f:
            raise MotionlangError(f"source output: weights {self.weights.shape} and means "
                                  f"{self.means.shape} do not fit the model's ({d},) sentence "
                                  f"embeddings and {f} features")
        return self

    def probabilities(self, z: torch.Tensor) -> torch.Tensor:
        """(B, D) sentence embeddings -> (B, S) each sentence's source probabilities."""
        if z.ndim != 2 or z.shape[1] != self.weights.shape[1]:
            raise MotionlangError(f"source output reads ({self.weights.shape[1]},) sentence "
                                  f"embeddings, got {tuple(z.shape)}")
        w = torch.as_tensor(self.weights, dtype=z.dtype, device=z.device)
        b = torch.as_tensor(self.bias, dtype=z.dtype, device=z.device)
        return torch.softmax(z @ w.T + b, dim=-1)

    def _mixed(self, p: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(B, S) -> each sentence's (B, 1, F) mean and spread."""
        mean = p @ torch.as_tensor(self.means, dtype=p.dtype, device=p.device)
        std = p @ torch.as_tensor(self.stds, dtype=p.dtype, device=p.device)
        return mean[:, None], std[:, None]

    def to_output(self, x: torch.Tensor, p: torch.Tensor, out) -> torch.Tensor:
        """(B, T, F) frames normalised by the sentences' sources (probabilities ``p`` (B, S))
        -> the same frames normalised by ``out`` (a ``Normalizer``: the model's features')."""
        mean, std = self._mixed(p.to(x.dtype))
        om = torch.as_tensor(np.asarray(out.mean), dtype=x.dtype, device=x.device)
        os_ = torch.as_tensor(np.asarray(out.std), dtype=x.dtype, device=x.device)
        return (x * std + mean - om) / os_

    def from_output(self, x: torch.Tensor, p: torch.Tensor, out) -> torch.Tensor:
        """The inverse of :meth:`to_output`, for (B, T, F) frames."""
        mean, std = self._mixed(p.to(x.dtype))
        om = torch.as_tensor(np.asarray(out.mean), dtype=x.dtype, device=x.device)
        os_ = torch.as_tensor(np.asarray(out.std), dtype=x.dtype, device=x.device)
        return (x * os_ + om - mean) / std

    def to_dict(self) -> dict:
        # plain Python types: checkpoints load with torch.load(weights_only=True)
        return {k: np.asarray(getattr(self, k)).tolist()
                for k in ("means", "stds", "weights", "bias")}

    @classmethod
    def from_dict(cls, d: dict) -> SourceOutput:
        return cls(d["means"], d["stds"], d["weights"], d["bias"])


def fit_source_output(model, sentences: Sequence[str], labels: Sequence[int],
                      normalizers: Sequence, *, seed: int = 0,
                      batch: int = 256) -> SourceOutput:
    """:meth:`SourceOutput.fit` on ``model``'s embeddings of (at most
    :data:`FIT_PER_SOURCE` of each source's) ``sentences``, whose sources are ``labels``;
    ``normalizers`` in source order."""
    rng = np.random.default_rng(seed)
    lab = np.asarray(labels)
    keep = np.concatenate([rng.permutation(np.flatnonzero(lab == s))[:FIT_PER_SOURCE]
                           for s in range(len(normalizers))])
    return SourceOutput.fit(normalizers, embed(model, [sentences[j] for j in keep], batch),
                            lab[keep])


def embed(model, sentences: Sequence[str], batch: int = 256) -> np.ndarray:
    """``model``'s sentence embeddings (``joint(encode_text(...))``), (N, D) float64, read
    in eval mode (the model's mode is restored)."""
    was = model.training
    model.eval()
    try:
        with torch.no_grad():
            return np.concatenate([model.joint(model.encode_text(list(sentences[i:i + batch])))
                                   .double().cpu().numpy()
                                   for i in range(0, len(sentences), batch)])
    finally:
        model.train(was)

"""The first pose of a generated motion, from its sentence.

The decoder unrolls from a first pose (Ghosh et al. 2021 start from the test motion's). In
training that is always the real motion's first frame, and it carries much of how the
motion is done: an actor asked for a feminine or an elderly walk stands so from the first
frame, and the decoder learns to keep the posture it is given and add the action the
sentence asks for. Started from one mean rest pose, every motion then begins, and mostly
stays, in a neutral posture. :class:`StartPose` is a ridge regression from the model's own
sentence embedding (``TwoStreamModel.joint`` of ``encode_text``, (B, D)) to the first frame
of the training motions (normalised features, (B, F)), so ``generate`` begins each motion in
a posture of the kind its sentence's motions begin in.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.schema import NUMBERS, ListOf
from motionlang.models.twostream.sources import embed

#: at most this many training pairs fit the regression (drawn at random)
FIT_PAIRS = 6000
#: a checkpoint's ``start_pose`` entry (:meth:`StartPose.to_dict`; None: the rest pose)
SCHEMA = (None, {"weights": ListOf(NUMBERS)})


@dataclass
class StartPose:
    """first pose = [z, 1] @ weights; ``weights`` (D + 1, F), the last row the bias."""

    weights: np.ndarray

    def __post_init__(self) -> None:
        self.weights = np.asarray(self.weights, dtype=np.float64)
        if self.weights.ndim != 2 or len(self.weights) < 2:
            raise MotionlangError(f"start pose: weights must be (D + 1, F), got "
                                  f"{self.weights.shape}")

    @classmethod
    def fit(cls, z: np.ndarray, first: np.ndarray, ridge: float = 1.0) -> StartPose:
        """Least squares from ``z`` (N, D) to ``first`` (N, F) with an L2 penalty ``ridge``
        on the weights (not the bias)."""
        z, first = np.asarray(z, dtype=np.float64), np.asarray(first, dtype=np.float64)
        if z.ndim != 2 or first.ndim != 2 or len(z) != len(first) or not len(z):
            raise MotionlangError(f"start pose: need (N, D) embeddings and (N, F) poses, "
                                  f"got {z.shape} and {first.shape}")
        x = np.hstack([z, np.ones((len(z), 1))])
        penalty = ridge * np.diag([1.0] * z.shape[1] + [0.0])
        return cls(np.linalg.solve(x.T @ x + penalty, x.T @ first))

    def checked(self, d: int, f: int) -> StartPose:
        """Itself, if it reads (D = ``d``,) embeddings into (F = ``f``,) poses."""
        if self.weights.shape != (d + 1, f):
            raise MotionlangError(f"start pose: weights {self.weights.shape} do not fit the "
                                  f"model's ({d},) sentence embeddings and {f} features")
        return self

    def predict(self, z: torch.Tensor) -> torch.Tensor:
        """(B, D) sentence embeddings -> (B, F) first poses (z's dtype), normalised as the
        decoder reads them: by the sentence's source's normaliser in a by-source model, else
        by the model's features'."""
        if z.ndim != 2 or z.shape[1] != len(self.weights) - 1:
            raise MotionlangError(f"start pose reads ({len(self.weights) - 1},) sentence "
                                  f"embeddings, got {tuple(z.shape)}")
        w = torch.as_tensor(self.weights, dtype=z.dtype, device=z.device)
        return z @ w[:-1] + w[-1]

    def to_dict(self) -> dict:
        # plain Python types: checkpoints load with torch.load(weights_only=True)
        return {"weights": self.weights.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> StartPose:
        return cls(d["weights"])


def fit_start_pose(model, sentences: Sequence[str], first: np.ndarray, *, seed: int = 0,
                   ridge: float = 1.0, batch: int = 256) -> StartPose:
    """:meth:`StartPose.fit` (penalty ``ridge``) on ``model``'s embeddings of (at most
    :data:`FIT_PAIRS` of) the training ``sentences`` and their motions' first frames
    ``first`` (N, F), normalised as the model's decoder reads them."""
    keep = np.random.default_rng(seed).permutation(len(sentences))[:FIT_PAIRS]
    z = embed(model, [sentences[j] for j in keep], batch)
    return StartPose.fit(z, np.asarray(first)[keep], ridge)


def decoder_start(model, z: dict[str, torch.Tensor], start, p: torch.Tensor | None
                  ) -> torch.Tensor:
    """(B, F) first poses for ``model``'s decoder, in the space it decodes in (each
    sentence's source's when ``model.sources``, probabilities ``p`` (B, S)): ``start`` (F,)
    or (B, F) normalised by the model's features, else each sentence's pose from
    ``model.start_pose`` (``z``: the sentences' embeddings), else ``model.rest_pose``.

    Raises:
        MotionlangError: ``start`` of another shape.
    """
    n = len(next(iter(z.values())))
    if start is None:
        return (model.rest_pose.expand(n, -1) if model.start_pose is None
                else model.start_pose.predict(model.joint(z)))
    x0 = torch.as_tensor(start, dtype=torch.float32, device=model.rest_pose.device)
    x0 = x0.expand(n, -1) if x0.ndim == 1 else x0
    f = model.config.n_features
    if x0.shape != (n, f):
        raise MotionlangError(f"start pose must be ({f},) or ({n}, {f}), got {tuple(x0.shape)}")
    if model.sources is not None and p is not None:
        x0 = model.sources.from_output(x0[:, None], p, model.normalizer)[:, 0].float()
    return x0

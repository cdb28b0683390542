"""Learning of a :class:`~motionlang.models.crbm.model.CRBM`: the CD-k gradients and the
minibatch loop with momentum and weight decay (a mixin of the model class)."""
from __future__ import annotations

import contextlib
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.models.crbm.config import PARAMS
from motionlang.models.crbm.sequences import check_sequences, chunk_index, gather_past
from motionlang.utils.progress import progress

if TYPE_CHECKING:
    from typing_extensions import Self

    from motionlang.models.crbm.config import CRBMConfig


def _blas_threads(n: int | None):
    """Limit BLAS threads while training (threadpoolctl, if installed; else no-op)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return contextlib.nullcontext()
    return threadpool_limits(limits=n, user_api="blas") if n else contextlib.nullcontext()


class CRBMTraining:
    """``cd_gradients`` and ``fit`` of :class:`~motionlang.models.crbm.model.CRBM` (which
    provides the parameters, ``config``, the conditionals and the normaliser)."""

    if TYPE_CHECKING:   # what the model class provides, declared for the type checker only
        config: CRBMConfig
        n_visible: int
        mean: np.ndarray
        std: np.ndarray
        history: list[float]

        def dynamic_biases(self, past: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...
        def hidden_probs(self, v: np.ndarray, b_star: np.ndarray) -> np.ndarray: ...
        def visible_mean(self, h: np.ndarray, a_star: np.ndarray) -> np.ndarray: ...
        def normalise(self, x: np.ndarray) -> np.ndarray: ...

    def cd_gradients(self, v0: np.ndarray, past: np.ndarray, rng: np.random.Generator | None
                     ) -> tuple[dict[str, np.ndarray], float]:
        """CD-k ascent direction, averaged over the N rows, for normalised ``v0`` (N, D)
        (k = ``config.cd_steps``; the negative chain starts at ``v0`` or, with
        ``negative_start="previous"``, at the past's latest frame).

        With ``rng`` the hidden states are sampled (the paper's rule); with ``rng=None``
        probabilities are used throughout, which makes the result a deterministic function:
        exactly ``-(d/dθ) mean[F(v0|p) - F(v1|p)]`` with the reconstruction v1 held fixed.
        Returns (gradients by parameter name, mean squared reconstruction error).
        """
        N, D = v0.shape
        cfg = self.config
        a_star, b_star = self.dynamic_biases(past)
        ph0 = self.hidden_probs(v0, b_star)

        def sample(p):
            return (p > rng.random(p.shape)).astype(v0.dtype) if rng is not None else p
        h0 = sample(ph0)
        if cfg.negative_start == "previous":   # past[:, :D] is frame t-1
            v1 = past[:, :D]
            h = sample(self.hidden_probs(v1, b_star))
        else:
            h = h0
        for k in range(cfg.cd_steps):
            v1 = self.visible_mean(h, a_star)
            ph1 = self.hidden_probs(v1, b_star)
            if k < cfg.cd_steps - 1:
                h = sample(ph1)
        dh = h0 - ph1                              # hidden-bias statistic, (N, H)
        dv = v0 - v1                               # visible-bias statistic, (N, D)
        grads = {
            "W": (v0.T @ h0 - v1.T @ ph1) / N,
            "a": dv.mean(axis=0),
            "b": dh.mean(axis=0),
            "A": past.T @ dv / N,
            "B": past.T @ dh / N,
        }
        return grads, float((dv ** 2).mean())

    def fit(self, sequences: Sequence[np.ndarray], *, show_progress: bool = False,
            epochs: int | None = None, on_epoch=None) -> Self:
        """Train on a list of (T_i, D) unnormalised sequences (T_i > order each).

        The normaliser is fitted here for Gaussian visibles (binary ones are used as is).
        ``on_epoch(epoch, model)`` (1-based epoch), if given, is called after every pass:
        it lets hyper-parameter selection score snapshots of one run at several epoch counts.
        """
        cfg = self.config
        seqs = check_sequences(sequences, self.n_visible, cfg.order + 1)
        frames = np.concatenate(seqs)
        if cfg.visible == "gaussian":
            self.mean = frames.mean(axis=0)
            sd = frames.std(axis=0)
            self.std = np.where(sd > 1e-8, sd, 1.0)
        x = self.normalise(frames).astype(self.config.dtype)
        rows = chunk_index([len(s) for s in seqs], cfg.order)
        rng = np.random.default_rng(cfg.seed + 1)
        velocity = {k: np.zeros_like(getattr(self, k)) for k in PARAMS}
        rates = {"W": cfg.lr, "B": cfg.lr, "a": cfg.lr, "b": cfg.lr, "A": cfg.lr_autoregressive}
        n_epochs = cfg.epochs if epochs is None else epochs
        epoch_iter = range(n_epochs)
        if show_progress:
            epoch_iter = progress(epoch_iter, desc="crbm", total=n_epochs)
        with _blas_threads(cfg.blas_threads):
            self._epochs(epoch_iter, x, rows, rng, velocity, rates, on_epoch)
        return self

    def _epochs(self, epoch_iter, x, rows, rng, velocity, rates, on_epoch=None) -> None:
        cfg = self.config
        wd_a = cfg.weight_decay if cfg.weight_decay_autoregressive is None else cfg.weight_decay_autoregressive
        decay = {"W": cfg.weight_decay, "B": cfg.weight_decay, "A": wd_a}
        for _ in epoch_iter:
            order = rng.permutation(rows)
            err = 0.0
            for start in range(0, len(order), cfg.batch_size):
                batch = order[start:start + cfg.batch_size]
                past = gather_past(x, batch, cfg.order)
                if cfg.history_noise > 0:
                    past = past + (cfg.history_noise
                                   * rng.standard_normal(past.shape)).astype(past.dtype)
                grads, e = self.cd_gradients(x[batch], past, rng)
                err += e * len(batch)
                for k in PARAMS:
                    g = grads[k]
                    if k in decay:
                        g = g - decay[k] * getattr(self, k)
                    velocity[k] *= cfg.momentum
                    velocity[k] += rates[k] * g
                    getattr(self, k).__iadd__(velocity[k])
            self.history.append(err / len(order))
            if not (np.isfinite(err) and all(np.isfinite(getattr(self, k)).all()
                                             for k in PARAMS)):
                raise MotionlangError(f"training stopped at epoch {len(self.history)}: the "
                                      "reconstruction error or weights are not finite (lower "
                                      "--lr)")
            if on_epoch is not None:
                on_epoch(len(self.history), self)

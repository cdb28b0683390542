"""Inference of a :class:`~motionlang.models.crbm.model.CRBM`: Gibbs updates of one frame,
causal generation, on-line filling of missing values and hidden activations (a mixin of
the model class)."""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.models.crbm.sequences import check_sequences, gather_past

if TYPE_CHECKING:
    from motionlang.models.crbm.config import CRBMConfig


class CRBMGeneration:
    """``gibbs_frame``, ``generate``, ``fill_in`` and ``hidden_activations`` of
    :class:`~motionlang.models.crbm.model.CRBM` (which provides ``config``, ``n_visible``,
    the conditionals and the normaliser)."""

    if TYPE_CHECKING:   # what the model class provides, declared for the type checker only
        config: CRBMConfig
        n_visible: int

        def dynamic_biases(self, past: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...
        def hidden_probs(self, v: np.ndarray, b_star: np.ndarray) -> np.ndarray: ...
        def visible_mean(self, h: np.ndarray, a_star: np.ndarray) -> np.ndarray: ...
        def normalise(self, x: np.ndarray) -> np.ndarray: ...
        def denormalise(self, x: np.ndarray) -> np.ndarray: ...

    def gibbs_frame(self, v: np.ndarray, past: np.ndarray, rng: np.random.Generator,
                    n_gibbs: int = 30, missing: np.ndarray | None = None,
                    hidden_noise: float = 0.0, mean_field: bool = False) -> np.ndarray:
        """Alternating Gibbs updates of one frame with its past fixed (all normalised).

        v (S, D) is the starting point (also the clamped values where ``missing`` (D,) or
        (S, D) is False); past (S, n*D). Hidden states are sampled except in the last
        update, where their probabilities give the mean-field visible (less jitter).
        ``hidden_noise`` is the std of Gaussian noise added to the hidden biases (one draw
        per frame), the paper's way of moving between styles. ``mean_field`` uses hidden
        probabilities in every update (deterministic). Returns the new v (S, D).
        """
        a_star, b_star = self.dynamic_biases(past)
        if hidden_noise > 0:
            b_star = b_star + hidden_noise * rng.standard_normal(b_star.shape)
        v = v.copy()
        for k in range(max(1, n_gibbs)):
            ph = self.hidden_probs(v, b_star)
            h = ph if (mean_field or k == n_gibbs - 1) else (ph > rng.random(ph.shape)).astype(v.dtype)
            mean = self.visible_mean(h, a_star)
            if missing is None:
                v = mean
            else:
                v = np.where(missing, mean, v)
        return v

    def generate(self, init: np.ndarray, n_frames: int, *, n_gibbs: int = 30, seed: int = 0,
                 hidden_noise: float = 0.0, n_samples: int = 1, mean_field: bool = False
                 ) -> np.ndarray:
        """Causal on-line generation from ``init`` (>= order real frames, (n0, D) unnormalised,
        or (S, n0, D) for S different starts generated side by side).

        Returns (n_samples or S, n0 + n_frames, D) unnormalised, starting with ``init``. Each new
        frame starts from the previous one and is refined by ``n_gibbs`` Gibbs updates
        (with hidden probabilities instead of samples if ``mean_field``: deterministic unless
        ``hidden_noise`` > 0).
        """
        n = self.config.order
        init = np.asarray(init)
        if init.ndim == 3:   # (S, n0, D): S different starts, one sequence each
            if n_samples != 1:
                raise MotionlangError("generate: give n_samples=1 with a batch of starts")
            init = np.stack(check_sequences(list(init), self.n_visible, n, "initial frames"))
            x = self.normalise(init)
            n_samples = len(init)
        else:
            init = check_sequences([init], self.n_visible, n, "initial frames")[0]
            x = np.repeat(self.normalise(init)[None], n_samples, axis=0)
        rng = np.random.default_rng(seed)
        n0 = x.shape[1]
        out = np.empty((n_samples, n0 + n_frames, self.n_visible))
        out[:, :n0] = x
        for t in range(n0, n0 + n_frames):
            past = out[:, t - n:t][:, ::-1].reshape(n_samples, -1)
            out[:, t] = self.gibbs_frame(out[:, t - 1], past, rng, n_gibbs,
                                         hidden_noise=hidden_noise, mean_field=mean_field)
        out = self.denormalise(out)
        out[:, :n0] = init   # exactly as given
        return out

    def fill_in(self, frames: np.ndarray, known: np.ndarray, *, n_gibbs: int = 30, seed: int = 0,
                n_samples: int = 1, mean_field: bool = False) -> np.ndarray:
        """Fill the unknown entries of ``frames`` (T, D) on-line, frame by frame.

        ``known`` is a (T, D) or (D,) boolean mask; the first ``order`` frames must be known.
        Unknown entries may hold anything (NaN included). Each frame with a gap starts from
        the previous (filled) frame on its missing dimensions, the known ones are clamped,
        and hidden/visible updates alternate. Known entries come back exactly as given.
        Returns (n_samples, T, D) unnormalised.
        """
        n = self.config.order
        frames = np.asarray(frames, dtype=np.float64)
        known = np.broadcast_to(np.asarray(known, dtype=bool), frames.shape)
        check = np.where(known, frames, 0.0)
        check_sequences([check], self.n_visible, n + 1, "fill-in sequence")
        if not known[:n].all():
            raise MotionlangError(f"fill_in: the first {n} frames (the model order) must be fully known")
        bad = ~np.isfinite(frames) & known
        if bad.any():
            f, d = np.argwhere(bad)[0]
            raise MotionFormatError("<fill-in sequence>", f"non-finite known value in dimension {d}",
                                    frame=int(f))
        rng = np.random.default_rng(seed)
        x = np.repeat(self.normalise(check)[None], n_samples, axis=0)
        for t in range(n, len(frames)):
            missing = ~known[t]
            if not missing.any():
                continue
            start = np.where(missing, x[:, t - 1], x[:, t])
            past = x[:, t - n:t][:, ::-1].reshape(n_samples, -1)
            x[:, t] = self.gibbs_frame(start, past, rng, n_gibbs, missing=missing,
                                       mean_field=mean_field)
        out = self.denormalise(x)
        out[:, known] = frames[known]   # bit-exact, not mean + std * (x - mean) / std
        return out

    def hidden_activations(self, sequences: Sequence[np.ndarray]) -> list[np.ndarray]:
        """p(h | v_t, past) for every frame with a full past: list of (T_i - order, H)."""
        n = self.config.order
        out = []
        for s in check_sequences(sequences, self.n_visible, n + 1):
            x = self.normalise(s)
            rows = np.arange(n, len(x))
            _, b_star = self.dynamic_biases(gather_past(x, rows, n))
            out.append(self.hidden_probs(x[rows], b_star))
        return out

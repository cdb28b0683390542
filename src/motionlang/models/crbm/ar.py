"""Order-n linear autoregressive model: the CRBM without its hidden layer (baseline).

    v_t = a + [v_{t-1}, ..., v_{t-n}] @ A + noise,   noise ~ N(0, I) in normalised units

Fitted in closed form (ridge-regularised least squares = maximum likelihood with an L2
prior), in the same normalised space and with the same past layout as :mod:`crbm`.
"""
from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.models.crbm.checkpoint import arrays, open_npz, read_config, read_meta
from motionlang.models.crbm.sequences import check_sequences, chunk_index, gather_past
from motionlang.models.versions import (
    DAMAGE,
    FORMAT_VERSION,
    check_format,
    load_problem,
)
from motionlang.utils.atomic import atomic_write


@dataclass
class ARConfig:
    order: int = 3
    ridge: float = 1e-3   # L2 weight on A, relative to the number of training rows


class ARModel:
    """Parameters A (n*D, D), a (D,); normaliser mean/std (D,)."""

    def __init__(self, config: ARConfig, n_visible: int):
        self.config = config
        self.n_visible = int(n_visible)
        nD = config.order * self.n_visible
        self.A = np.zeros((nD, self.n_visible))
        self.a = np.zeros(self.n_visible)
        self.mean = np.zeros(self.n_visible)
        self.std = np.ones(self.n_visible)

    def normalise(self, x: np.ndarray) -> np.ndarray:
        return (np.asarray(x, dtype=np.float64) - self.mean) / self.std

    def denormalise(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x) * self.std + self.mean

    def fit(self, sequences: Sequence[np.ndarray]) -> ARModel:
        """Least squares on all frames with a full past; sequences (T_i, D) unnormalised."""
        n = self.config.order
        seqs = check_sequences(sequences, self.n_visible, n + 1)
        frames = np.concatenate(seqs)
        self.mean = frames.mean(axis=0)
        sd = frames.std(axis=0)
        self.std = np.where(sd > 1e-8, sd, 1.0)
        x = self.normalise(frames)
        rows = chunk_index([len(s) for s in seqs], n)
        P = np.hstack([gather_past(x, rows, n), np.ones((len(rows), 1))])
        reg = self.config.ridge * len(rows) * np.eye(P.shape[1])
        reg[-1, -1] = 0.0  # no shrinkage of the bias
        coef = np.linalg.solve(P.T @ P + reg, P.T @ x[rows])
        self.A, self.a = coef[:-1], coef[-1]
        return self

    def predict_normalised(self, past: np.ndarray) -> np.ndarray:
        """past (N, n*D) normalised -> mean of the next frame (N, D) normalised."""
        return self.a + past @ self.A

    def generate(self, init: np.ndarray, n_frames: int, *, noise: float = 0.0,
                 seed: int = 0) -> np.ndarray:
        """Roll the model forward from ``init`` ((>= order, D) unnormalised); returns
        (len(init) + n_frames, D) unnormalised. ``noise`` scales the unit-variance noise."""
        n = self.config.order
        init = check_sequences([init], self.n_visible, n, "initial frames")[0]
        rng = np.random.default_rng(seed)
        x = np.empty((len(init) + n_frames, self.n_visible))
        x[:len(init)] = self.normalise(init)
        for t in range(len(init), len(x)):
            x[t] = self.predict_normalised(x[t - n:t][::-1].reshape(1, -1))[0]
            if noise > 0:
                x[t] += noise * rng.standard_normal(self.n_visible)
        out = self.denormalise(x)
        out[:len(init)] = init
        return out

    def fill_in(self, frames: np.ndarray, known: np.ndarray) -> np.ndarray:
        """Unknown entries of ``frames`` (T, D) := the prediction from the (filled) past.

        ``known`` (T, D) or (D,) bool; the first ``order`` frames must be known. Returns
        (T, D) unnormalised with the known entries exactly as given.
        """
        n = self.config.order
        frames = np.asarray(frames, dtype=np.float64)
        known = np.broadcast_to(np.asarray(known, dtype=bool), frames.shape)
        check_sequences([np.where(known, frames, 0.0)], self.n_visible, n + 1, "fill-in sequence")
        if not known[:n].all():
            raise MotionlangError(f"fill_in: the first {n} frames (the model order) must be fully known")
        x = self.normalise(np.where(known, frames, 0.0))
        for t in range(n, len(x)):
            if not known[t].all():
                pred = self.predict_normalised(x[t - n:t][::-1].reshape(1, -1))[0]
                x[t] = np.where(known[t], x[t], pred)
        out = self.denormalise(x)
        out[known] = frames[known]
        return out

    def save(self, path: str | Path) -> None:
        meta = {"kind": "ar", "version": FORMAT_VERSION, "config": dataclasses.asdict(self.config),
                "n_visible": self.n_visible}
        with atomic_write(path, "wb") as fh:
            np.savez(fh, meta=np.array(json.dumps(meta)), A=self.A, a=self.a,
                     mean=self.mean, std=self.std)

    @classmethod
    def load(cls, path: str | Path) -> ARModel:
        try:
            with open_npz(path) as z:
                meta = read_meta(path, z, "meta", "ar")
                if meta.get("kind") != "ar":
                    raise MotionFormatError(path, f"not an AR checkpoint (kind={meta.get('kind')!r})")
                check_format(path, meta.get("version", 0))
                config, D = read_config(path, meta, "ar", ARConfig)
                stored = arrays(path, z, "ar", {"A": (config.order * D, D), "a": (D,),
                                                "mean": (D,), "std": (D,)})
                model = cls(config, D)
                for k in ("A", "a", "mean", "std"):
                    setattr(model, k, stored[k].astype(np.float64))
        except (OSError, *DAMAGE) as exc:
            raise MotionFormatError(path, load_problem("ar", exc)) from exc
        return model

"""Conditional restricted Boltzmann machine (Taylor, Hinton & Roweis 2006).

Visible units ``v_t`` (D,) are real valued with unit variance (the model normalises its
input to zero mean, unit standard deviation per dimension) or binary (for a second level
trained on the first one's hidden activations); hidden units ``h_t`` (H,) are binary.
The past ``n`` frames ``p_t = [v_{t-1}, ..., v_{t-n}]`` (n*D,) act as dynamic biases:

    a*_t = a + p_t @ A        (visible,  A: (n*D, D))
    b*_t = b + p_t @ B        (hidden,   B: (n*D, H))
    F(v | p) = 0.5 |v - a*|^2 - sum_j softplus(b*_j + v @ W_j)     (Gaussian visibles)
    F(v | p) = -v @ a*         - sum_j softplus(b*_j + v @ W_j)     (binary visibles)

Training is CD-1 with the paper's approximations: the hidden states are sampled (binary)
for the positive statistics and for the reconstruction, the reconstruction is the visible
mean (no visible noise), and the negative statistics use hidden probabilities.

All public methods take and return *unnormalised* features; the mean and standard
deviation learnt by :meth:`CRBM.fit` are part of the checkpoint.

Training (CD-k, :mod:`.training`) and inference (:mod:`.generation`) are mixins of
:class:`CRBM`; the config is in :mod:`.config`.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.models.crbm.checkpoint import (
    arrays,
    crbm_shapes,
    open_npz,
    read_config,
    read_meta,
)
from motionlang.models.crbm.config import PARAMS, CRBMConfig
from motionlang.models.crbm.generation import CRBMGeneration
from motionlang.models.crbm.training import CRBMTraining
from motionlang.models.versions import (
    DAMAGE,
    FORMAT_VERSION,
    check_format,
    load_problem,
)
from motionlang.utils.atomic import atomic_write


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * x))  # overflow-free logistic


class CRBM(CRBMTraining, CRBMGeneration):
    """A trained or trainable CRBM. Parameters: W (D,H), A (nD,D), B (nD,H), a (D,), b (H,)."""

    def __init__(self, config: CRBMConfig, n_visible: int):
        self.config = config
        self.n_visible = int(n_visible)
        rng = np.random.default_rng(config.seed)
        D, H, nD = self.n_visible, config.n_hidden, self.n_visible * config.order
        s = config.init_std
        dt = np.dtype(config.dtype)
        self.W = (s * rng.standard_normal((D, H))).astype(dt)
        self.A = (s * rng.standard_normal((nD, D))).astype(dt)
        self.B = (s * rng.standard_normal((nD, H))).astype(dt)
        self.a = np.zeros(D, dtype=dt)
        self.b = np.zeros(H, dtype=dt)
        self.mean = np.zeros(D)   # normaliser, set by fit()
        self.std = np.ones(D)
        self.history: list[float] = []   # mean squared reconstruction error per epoch

    # ----------------------------------------------------------------- conditionals
    def dynamic_biases(self, past: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """past (N, n*D) normalised -> (a* (N, D), b* (N, H))."""
        return self.a + past @ self.A, self.b + past @ self.B

    def hidden_probs(self, v: np.ndarray, b_star: np.ndarray) -> np.ndarray:
        """p(h=1 | v, past): (N, H)."""
        return _sigmoid(b_star + v @ self.W)

    def visible_mean(self, h: np.ndarray, a_star: np.ndarray) -> np.ndarray:
        """E[v | h, past]: (N, D); Gaussian mean or Bernoulli probability."""
        x = a_star + h @ self.W.T
        return x if self.config.visible == "gaussian" else _sigmoid(x)

    def free_energy(self, v: np.ndarray, past: np.ndarray) -> np.ndarray:
        """F(v | past) per row, (N,); p(v | past) is proportional to exp(-F)."""
        a_star, b_star = self.dynamic_biases(past)
        x = b_star + v @ self.W
        soft = np.logaddexp(0.0, x).sum(axis=1)
        if self.config.visible == "gaussian":
            return 0.5 * ((v - a_star) ** 2).sum(axis=1) - soft
        return -(v * a_star).sum(axis=1) - soft

    # ----------------------------------------------------------------- normaliser
    def normalise(self, x: np.ndarray) -> np.ndarray:
        return (np.asarray(x, dtype=np.float64) - self.mean) / self.std

    def denormalise(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x) * self.std + self.mean

    # ----------------------------------------------------------------- save / load
    def save(self, path: str | Path) -> None:
        """One self-describing .npz: config (JSON), parameters, normaliser, training curve."""
        meta = {"kind": "crbm", "version": FORMAT_VERSION, "config": dataclasses.asdict(self.config),
                "n_visible": self.n_visible}
        arrays = {k: getattr(self, k) for k in PARAMS}
        with atomic_write(path, "wb") as fh:
            np.savez(fh, meta=np.array(json.dumps(meta)), mean=self.mean, std=self.std,
                     history=np.asarray(self.history, dtype=np.float64), **arrays)

    @classmethod
    def load(cls, path: str | Path) -> CRBM:
        try:
            with open_npz(path) as z:
                meta = read_meta(path, z, "meta", "crbm")
                if meta.get("kind") != "crbm":
                    raise MotionFormatError(path, f"not a CRBM checkpoint (kind={meta.get('kind')!r})")
                check_format(path, meta.get("version", 0))
                config, n_visible = read_config(path, meta, "crbm", CRBMConfig)
                stored = arrays(path, z, "crbm", crbm_shapes(config, n_visible))
                history = arrays(path, z, "crbm", {"history": z["history"].shape}
                                 if "history" in z.files else {"history": (0,)})["history"]
                model = cls(config, n_visible)
                for k in PARAMS:
                    setattr(model, k, stored[k].astype(model.config.dtype))
                for k in ("mean", "std"):
                    setattr(model, k, stored[k].astype(np.float64))
                model.history = history.reshape(-1).tolist()
        except (OSError, *DAMAGE) as exc:
            raise MotionFormatError(path, load_problem("crbm", exc)) from exc
        return model

    def describe(self) -> str:
        c = self.config
        return (f"CRBM order {c.order}, {self.n_visible} {c.visible} visible, {c.n_hidden} hidden, "
                f"trained {len(self.history)} epochs"
                + (f", final reconstruction MSE {self.history[-1]:.4f}" if self.history else ""))

"""Per-dimension z-score normalisation of feature arrays (numpy or torch).

A :class:`Normalizer` is fitted once on training features and then travels with the model
(``to_dict`` / ``from_dict`` embed it in a checkpoint) so that sampling undoes exactly the
normalisation that training applied.
"""
from __future__ import annotations

import json
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.utils.atomic import atomic_path, atomic_write
from motionlang.utils.sidecar import load_json


def _is_torch(x: Any) -> bool:
    return type(x).__module__.startswith("torch")


@dataclass
class Normalizer:
    """``transform(x) = (x - mean) / std`` per feature dimension.

    Attributes:
        mean: (D,) per-dimension mean of the training data.
        std: (D,) per-dimension standard deviation; dimensions whose spread is below
            ``min_std`` (constant or almost constant) get std 1 so they are only centred —
            dividing by a tiny std would blow up noise in a dimension that carries nothing.
        min_std: the floor described above (in the feature's own unit).
        names: optional (D,) names of the dimensions, kept for self-description.
    """

    mean: np.ndarray | None = None
    std: np.ndarray | None = None
    min_std: float = 1e-6
    names: list[str] | None = field(default=None)

    # ------------------------------------------------------------------ fitting
    def fit(self, x: np.ndarray | Sequence[np.ndarray]) -> Normalizer:
        """Fit on x (N, D), on (..., D), or on a list of (T_i, D) arrays (concatenated).

        Raises:
            MotionlangError: on empty data or non-finite values.
        """
        if isinstance(x, (list, tuple)):
            if not x:
                raise MotionlangError("Normalizer.fit: no data")
            x = np.concatenate([np.asarray(a, dtype=np.float64).reshape(-1, np.shape(a)[-1])
                                for a in x])
        x = np.asarray(x, dtype=np.float64)
        x = x.reshape(-1, x.shape[-1])
        if len(x) == 0:
            raise MotionlangError("Normalizer.fit: no data")
        if not np.all(np.isfinite(x)):
            raise MotionlangError("Normalizer.fit: non-finite values in the data")
        self.mean = x.mean(axis=0)
        std = x.std(axis=0)
        self.std = np.where(std < self.min_std, 1.0, std)
        return self

    @property
    def dim(self) -> int:
        self._check()
        return len(self.mean)

    def _check(self) -> None:
        if self.mean is None or self.std is None:
            raise MotionlangError("Normalizer is not fitted (call fit or load first)")

    def _stats(self, x):
        """mean and std broadcastable against x, in x's array library, dtype and device."""
        self._check()
        if x.shape[-1] != len(self.mean):
            raise MotionlangError(f"Normalizer expects {len(self.mean)} dimensions, "
                                  f"got {x.shape[-1]}")
        if _is_torch(x):
            import torch
            return (torch.as_tensor(self.mean, dtype=x.dtype, device=x.device),
                    torch.as_tensor(self.std, dtype=x.dtype, device=x.device))
        dtype = x.dtype if np.issubdtype(x.dtype, np.floating) else np.float64
        return self.mean.astype(dtype), self.std.astype(dtype)

    # ------------------------------------------------------------------ apply
    def transform(self, x):
        """x (..., D) numpy array or torch tensor -> normalised, same type and dtype."""
        if not _is_torch(x):
            x = np.asarray(x)
        mean, std = self._stats(x)
        return (x - mean) / std

    def inverse(self, z):
        """Undo :meth:`transform`: z (..., D) -> x (..., D), same type and dtype."""
        if not _is_torch(z):
            z = np.asarray(z)
        mean, std = self._stats(z)
        return z * std + mean

    # ------------------------------------------------------------------ persistence
    def to_dict(self) -> dict:
        """Plain-JSON description (lists of floats), for checkpoints."""
        self._check()
        return {"type": "Normalizer", "mean": [float(v) for v in self.mean],
                "std": [float(v) for v in self.std], "min_std": float(self.min_std),
                "names": None if self.names is None else list(self.names)}

    @classmethod
    def from_dict(cls, d: dict) -> Normalizer:
        """Inverse of :meth:`to_dict`."""
        if d.get("type", "Normalizer") != "Normalizer":
            raise MotionlangError(f"not a Normalizer description: type {d.get('type')!r}")
        try:
            mean = np.asarray(d["mean"], dtype=np.float64)
            std = np.asarray(d["std"], dtype=np.float64)
        except (KeyError, TypeError, ValueError) as e:
            raise MotionlangError(f"bad Normalizer description: {e}") from None
        if mean.shape != std.shape or mean.ndim != 1 or np.any(std <= 0):
            raise MotionlangError("bad Normalizer description: mean/std must be equal-length "
                                  "1-D lists with positive std")
        return cls(mean=mean, std=std, min_std=float(d.get("min_std", 1e-6)),
                   names=d.get("names"))

    def save(self, path: str | Path) -> None:
        """Write to ``.json`` (readable) or ``.npz`` (exact float64), chosen by extension."""
        path = Path(path)
        d = self.to_dict()
        if path.suffix == ".npz":
            with atomic_path(path) as tmp:
                np.savez(tmp, mean=self.mean, std=self.std, min_std=self.min_std,
                         names=np.array(self.names if self.names is not None else [], dtype=str))
        else:
            with atomic_write(path) as fh:
                json.dump(d, fh)

    @classmethod
    def load(cls, path: str | Path) -> Normalizer:
        """Read a ``.json`` or ``.npz`` file written by :meth:`save`."""
        path = Path(path)
        try:
            if path.suffix == ".npz":
                with np.load(path) as z:
                    names = [str(n) for n in z["names"]] or None
                    return cls.from_dict({"mean": z["mean"], "std": z["std"],
                                          "min_std": float(z["min_std"]), "names": names})
            return cls.from_dict(load_json(path, "normaliser"))
        except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as e:
            raise MotionlangError(f"{path}: cannot read normaliser: {e}") from None

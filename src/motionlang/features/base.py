"""What every feature representation shares: a config dataclass, a fitted normaliser,
self-describing ``to_dict`` / ``from_dict`` / ``save`` / ``load``, and frame-rate changes.

A feature class subclasses :class:`FeatureSet`, sets ``kind`` and ``Config``, and
implements ``_state`` / ``_set_state`` for whatever it learns in ``fit`` besides the
normaliser. :func:`features_from_dict` rebuilds any of them from a checkpoint entry.
"""
from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.normalizer import Normalizer
from motionlang.kinematics.motion import Motion
from motionlang.utils.atomic import atomic_write

#: kind -> feature class, filled by ``FeatureSet.__init_subclass__``; ``motionlang.features``
#: imports the built-in kinds, so they are here before any of its modules is used
_REGISTRY: dict[str, type[FeatureSet]] = {}


def downsample(motion: Motion, fps: float, offset: int = 0) -> Motion:
    """``motion`` at ``fps``: exact frames ``offset::step`` when ``motion.fps / fps`` is an
    integer ``step`` (100 -> 10 Hz, 120 -> 30 Hz), else linear re-timing (offset must be 0)."""
    ratio = motion.fps / fps
    step = int(round(ratio))
    if step >= 1 and abs(ratio - step) < 1e-9:
        if not 0 <= offset < step:
            raise ValueError(f"offset {offset} outside 0..{step - 1}")
        return motion[offset::step]
    if offset:
        raise ValueError(f"offsets need an integer frame-rate ratio, got {motion.fps}/{fps}")
    return motion.resample(fps)


def as_numpy(x) -> np.ndarray:
    """numpy float64 copy of an array or (CPU/GPU, grad or not) torch tensor."""
    if type(x).__module__.startswith("torch"):
        x = x.detach().cpu().numpy()
    return np.asarray(x, dtype=np.float64)


class FeatureSet:
    """Base of the feature representations (see module docstring)."""

    kind: ClassVar[str] = ""
    Config: ClassVar[type] = object
    #: whether the whole encoding is ``encode_rows(rows(motion))`` and ``fit`` is
    #: ``fit_rows`` of those rows, small arrays at the features' rate: a dataset reader
    #: then keeps them and reads each motion once
    encodes_rows: ClassVar[bool] = False

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        if cls.kind:
            _REGISTRY[cls.kind] = cls

    def __init__(self, config=None, **options):
        self.config = config if config is not None else self.Config(**options)
        self.normalizer: Normalizer | None = None

    # ------------------------------------------------------------------ interface
    @property
    def fps(self) -> float:
        """Frame rate of the encoded sequences."""
        return float(self.config.fps)

    @property
    def names(self) -> list[str]:  # pragma: no cover - subclasses override
        raise NotImplementedError

    @property
    def dim(self) -> int:
        """Number of feature dimensions D of ``encode``'s output (T, D)."""
        return len(self.names)

    @property
    def fitted(self) -> bool:
        return self.normalizer is not None

    def rows(self, motion: Motion) -> np.ndarray:  # pragma: no cover
        """The un-normalised features of ``motion`` that :meth:`fit` reads and
        :meth:`encode_rows` normalises (where :attr:`encodes_rows`)."""
        raise NotImplementedError

    def fit_rows(self, rows: Sequence[np.ndarray]) -> FeatureSet:  # pragma: no cover
        """:meth:`fit` from :meth:`rows` of the motions (where :attr:`encodes_rows`)."""
        raise NotImplementedError

    def encode_rows(self, rows: np.ndarray) -> np.ndarray:  # pragma: no cover
        """:meth:`encode` from the motion's :meth:`rows` (where :attr:`encodes_rows`)."""
        raise NotImplementedError

    def _require_fit(self) -> None:
        if self.normalizer is None:
            raise MotionlangError(f"{type(self).__name__} is not fitted (call fit or load)")

    def _out(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x, dtype=getattr(self.config, "dtype", "float32"))

    # ------------------------------------------------------------------ persistence
    def _state(self) -> dict[str, Any]:
        return {}

    def _set_state(self, state: dict[str, Any]) -> None:
        pass

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description: kind, config, normaliser and fitted state."""
        self._require_fit()
        return {"kind": self.kind, "config": asdict(self.config),
                "normalizer": self.normalizer.to_dict(), "state": self._state(),
                "names": self.names}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FeatureSet:
        """Inverse of :meth:`to_dict` (unknown config keys are ignored)."""
        if cls.kind and d.get("kind") != cls.kind:
            raise MotionlangError(f"expected {cls.kind!r} features, got {d.get('kind')!r}")
        known = {f.name for f in fields(cls.Config)}
        obj = cls(cls.Config(**{k: v for k, v in d.get("config", {}).items() if k in known}))
        obj.normalizer = Normalizer.from_dict(d["normalizer"])
        obj._set_state(d.get("state", {}))
        return obj

    def save(self, path: str | Path) -> None:
        """Write :meth:`to_dict` as JSON (atomically)."""
        with atomic_write(path) as fh:
            json.dump(self.to_dict(), fh)

    @classmethod
    def load(cls, path: str | Path) -> FeatureSet:
        """Read a file written by :meth:`save`; on the base class, of any registered kind."""
        try:
            with open(path, encoding="utf-8") as fh:
                d = json.load(fh)
        except (OSError, ValueError) as e:
            raise MotionlangError(f"{path}: cannot read features: {e}") from None
        return cls.from_dict(d) if cls.kind else features_from_dict(d)


def _feature_class(kind: Any) -> type[FeatureSet]:
    # the built-in kinds are registered: importing this module runs the package's
    # __init__ first, which imports them (importing them here would be an import circle)
    if kind not in _REGISTRY:
        raise MotionlangError(f"unknown feature kind {kind!r}; known: {sorted(_REGISTRY)}")
    return _REGISTRY[kind]


def features_from_dict(d: dict[str, Any]) -> FeatureSet:
    """Rebuild any registered feature set (``"angles"``, ``"positions"``, ``"taylor"``)."""
    return _feature_class(d.get("kind")).from_dict(d)


def make_features(kind: str, options: dict[str, Any] | None = None) -> FeatureSet:
    """A new, unfitted feature set of ``kind`` whose config fields are ``options``.

    Raises:
        MotionlangError: unknown kind or option name.
    """
    cls = _feature_class(kind)
    try:
        return cls(**dict(options or {}))
    except TypeError as exc:  # an option the config dataclass does not have
        raise MotionlangError(f"{kind} features: {exc}") from None

"""Text-conditioned in-betweening for any text-to-motion model that can fill in: the frames
of a motion to keep (its start and end, keyframes, everything but a time range), the rest
generated from a sentence (``generate TEXT --keep FILE:0-2s,8-10s``,
``ml.generate(text, model, keep=...)``).

A family offers it by giving its model an ``inbetween`` method (:class:`Inbetweening`);
the masked-token family does, by masking only the tokens of frames not kept.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from motionlang.datasets.text import tokenize
from motionlang.errors import MotionlangError
from motionlang.features.positions import PositionFeatures, PositionsConfig

Spans = list[tuple[float, float | None]]


@runtime_checkable
class Inbetweening(Protocol):
    """A model that fills in motion: ``inbetween(text, p21, keep, *, seed, options,
    foot_lock)`` with global positions (T, 21, 3) metres at ``fps`` and kept frames (T,)
    bool -> (T, 21, 3), the kept frames as given (``foot_lock``: the generated frames'
    planted feet held)."""

    @property
    def fps(self) -> float: ...

    def inbetween(self, text: str, p21: np.ndarray, keep: np.ndarray, *, seed: int,
                  options: Any, foot_lock: bool) -> np.ndarray: ...


def _seconds(text: str, spec: str) -> float:
    try:
        value = float(text[:-1] if text.endswith("s") else text)
    except ValueError:
        raise MotionlangError(f"--keep {spec}: {text!r} is not a time in seconds") from None
    if not np.isfinite(value) or value < 0:
        raise MotionlangError(f"--keep {spec}: {text!r} is not a time >= 0")
    return value


def parse_keep(spec: Any) -> tuple[Any, Spans]:
    """``"FILE:0-2s,8-10s"`` -> ``(FILE, [(0.0, 2.0), (8.0, 10.0)])``: the motion and the
    time ranges of it to keep, in seconds (the ``s`` is optional; ``8-`` runs to the end).
    A pair ``(motion or file, [(t0, t1), ...])`` is returned as it is.

    Raises:
        MotionlangError: no ranges, a range that is not ``A-B`` with A < B.
    """
    if isinstance(spec, (tuple, list)) and len(spec) == 2:
        source, given = spec
        return source, [(float(a), None if b is None else float(b)) for a, b in given]
    text = str(spec)
    source, sep, ranges = text.rpartition(":")
    if not sep or not source or not ranges.strip():
        raise MotionlangError(f"--keep {text}: expected FILE:RANGES, e.g. walk.bvh:0-2s,8-10s")
    spans: Spans = []
    for part in ranges.split(","):
        a, dash, b = part.strip().partition("-")
        if not dash or not a:
            raise MotionlangError(f"--keep {text}: {part!r} is not a range A-B (seconds)")
        start, end = _seconds(a, text), (_seconds(b, text) if b else None)
        if end is not None and end <= start:
            raise MotionlangError(f"--keep {text}: the range {part!r} ends before it starts")
        spans.append((start, end))
    return source, spans


def keep_frames(n_frames: int, fps: float, spans: Sequence[tuple[float, float | None]],
                where: str = "--keep") -> np.ndarray:
    """(n_frames,) bool: True for the frames whose time (t / fps) lies in a span (ends
    included; an end of None: to the last frame).

    Raises:
        MotionlangError: a span that starts after the motion ends, no frame kept, or every
            frame kept (nothing to generate).
    """
    t = np.arange(n_frames) / fps
    keep = np.zeros(n_frames, dtype=bool)
    for a, b in spans:
        if a > t[-1] + 1e-9:
            raise MotionlangError(f"{where}: the range from {a:g} s starts after the motion "
                                  f"ends ({t[-1]:.2f} s)")
        keep |= (t >= a - 1e-9) & (t <= (np.inf if b is None else b + 1e-9))
    if keep.all():
        raise MotionlangError(f"{where}: the ranges keep every frame; nothing to generate")
    return keep


def fill_between(t2m: Any, text: str, keep: Any, read: Callable[[Any], Any], *,
                 seed: int = 0, foot_lock: bool = False) -> list[tuple[np.ndarray, float]]:
    """The kept spans of a motion (``keep``: as :func:`parse_keep` reads it; ``read`` turns
    its motion or file into a ``Motion`` of any rig the 21-joint body maps) with the rest
    generated for ``text`` by ``t2m`` (a ``models.t2m.TextToMotion``): one hypothesis
    ``[(positions (T, 21, 3) metres at the model's fps, NaN)]``, placed where the motion
    is. ``foot_lock``: the generated frames' planted feet held, before they are joined to
    the kept ones and again after.

    Raises:
        MotionlangError: a model that cannot fill in, a sentence without words, spans that
            keep nothing or everything.
    """
    source, spans = parse_keep(keep)   # a malformed --keep first, before any file is read
    model = t2m.model
    if not isinstance(model, Inbetweening):
        raise MotionlangError(f"a {getattr(model, 'kind', type(model).__name__)} model does "
                              "not fill in motion (--keep needs one that does, such as a "
                              "masked-token model)")
    if not tokenize(text):
        raise MotionlangError(f"text {text!r} has no words to generate a motion from")
    motion = read(source)
    p21 = PositionFeatures(PositionsConfig(fps=float(model.fps))).body(motion)
    keep = keep_frames(len(p21), float(model.fps), spans)
    name = getattr(motion, "name", None) or (str(motion) if isinstance(motion, Path) else "")
    if not keep.any():
        raise MotionlangError(f"--keep: no frame of {name or 'the motion'} is in the ranges")
    out = model.inbetween(text, p21, keep, seed=seed, options=t2m.options, foot_lock=foot_lock)
    return [(np.asarray(out, dtype=np.float64), float("nan"))]

"""Overlapping time windows over a take: what an index embeds and what a timeline describes.

A long recording walks, jumps and turns; one vector or one sentence for all of it says
nothing. Cutting it into windows of a few seconds that overlap (a hop shorter than the
window) gives every action at least one window that holds most of it, wherever it starts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from motionlang.errors import MotionlangError
from motionlang.kinematics.motion import Motion


@dataclass(frozen=True)
class Window:
    """A span of a take in seconds, ``start`` <= t <= ``end``."""

    start: float
    end: float

    @property
    def length(self) -> float:
        return self.end - self.start

    def overlaps(self, other: Window) -> bool:
        return self.start < other.end and other.start < self.end


def windows(duration: float, length: float = 3.0, hop: float = 1.0) -> list[Window]:
    """Windows of ``length`` seconds every ``hop`` seconds over ``duration`` seconds, the
    last one ending at the take's end (so no tail is left out); a take shorter than
    ``length`` is one window over all of it.

    Raises:
        MotionlangError: a length, hop or duration that is not a finite positive number.
    """
    for name, value in (("duration", duration), ("length", length), ("hop", hop)):
        if not (math.isfinite(value) and value > 0):
            raise MotionlangError(f"window {name} must be a finite number > 0, got {value}")
    if duration <= length:
        return [Window(0.0, float(duration))]
    starts = [k * hop for k in range(int(math.floor((duration - length) / hop + 1e-9)) + 1)]
    if starts[-1] + length < duration - 1e-9:   # the tail gets a window of its own
        starts.append(duration - length)
    return [Window(round(s, 6), round(s + length, 6)) for s in starts]


def span(motion: Motion) -> float:
    """Seconds from the first frame to the last (0 for one frame)."""
    return (motion.n_frames - 1) / motion.fps


def cut(motion: Motion, window: Window) -> Motion:
    """The frames of ``motion`` inside ``window`` (both ends included)."""
    return motion.between(window.start, min(window.end, span(motion)))


def motion_windows(motion: Motion, length: float = 3.0, hop: float = 1.0
                   ) -> list[tuple[Window, Motion]]:
    """``(window, its frames)`` over the whole of ``motion`` (:func:`windows`); a take of
    one frame is one window of it."""
    if motion.n_frames < 2:
        return [(Window(0.0, 0.0), motion)]
    return [(w, cut(motion, w)) for w in windows(span(motion), length, hop)]

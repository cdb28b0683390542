"""What a detector says: a finding with its time span, the quantity it measured, the threshold
it compared against and a confidence, so that every phrase of a grounded sentence can show
where it came from (``describe --explain``).

A finding is only made where the evidence is clear; :func:`confidence` turns the margin by
which a measured quantity passes its threshold into 0..1, and the detectors drop what stays
below :data:`MIN_CONFIDENCE` rather than guess.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

#: findings below this confidence are not reported at all: the layer stays silent instead
MIN_CONFIDENCE = 0.5


@dataclass(frozen=True)
class Finding:
    """One thing the body does, with its evidence.

    Attributes:
        kind: the family of the finding: ``"posture"``, ``"locomotion"``, ``"turn"``,
            ``"level"`` or ``"limb"``.
        label: what it is (``"sit"``, ``"walk"``, ``"punch"``, ... : ``analysis.LABELS``).
        start, end: seconds from the first frame (end exclusive).
        measure: the quantity the decision rests on, in words (``"pelvis height / leg"``).
        value: its measured value (median over the span, or the peak for an event).
        threshold: the value it was compared with (same unit).
        confidence: 0..1 (:func:`confidence`).
        side: ``"left"``, ``"right"``, ``"both"`` or None.
        count: repetitions within the span (steps of a hop, punches, waves), 1 for one.
        detail: label-specific words and numbers (direction, speed word, angle, face).
    """

    kind: str
    label: str
    start: float
    end: float
    measure: str
    value: float
    threshold: float
    confidence: float
    side: str | None = None
    count: int = 1
    detail: dict[str, Any] = field(default_factory=dict)

    @property
    def duration(self) -> float:
        return self.end - self.start

    def shifted(self, seconds: float) -> Finding:
        """The same finding ``seconds`` later (its span and any event times in ``detail``)."""
        detail = dict(self.detail)
        if "times" in detail:
            detail["times"] = [round(t + seconds, 2) for t in detail["times"]]
        return replace(self, start=self.start + seconds, end=self.end + seconds,
                       detail=detail)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready, numbers rounded to what a reader can use."""
        d = asdict(self)
        for k in ("start", "end", "value", "threshold", "confidence"):
            d[k] = round(float(d[k]), 3)
        d["detail"] = {k: (round(float(v), 3) if isinstance(v, (float, np.floating)) else v)
                       for k, v in self.detail.items()}
        return d

    def evidence(self) -> str:
        """One line: span, measure, value against threshold, confidence."""
        side = f" {self.side}" if self.side else ""
        count = f" x{self.count}" if self.count > 1 else ""
        return (f"{self.start:6.2f}-{self.end:6.2f} s  {self.label}{side}{count}: "
                f"{self.measure} {self.value:.2f} (threshold {self.threshold:.2f}), "
                f"confidence {self.confidence:.2f}")


def confidence(value: float, threshold: float, scale: float, *, duration: float = 1.0,
               full_after: float = 0.0) -> float:
    """0..1: how clearly ``value`` passes ``threshold`` (positive ``scale``: above it,
    negative: below it), ``scale`` being the margin that counts as clear; a finding shorter
    than ``full_after`` seconds loses confidence in proportion.

    At the threshold itself the confidence is 0.5: a measurement that only just passes is
    a coin toss, and :data:`MIN_CONFIDENCE` keeps it out only if anything else lowers it."""
    if not np.isfinite(value):
        return 0.0
    margin = (value - threshold) / scale
    c = float(np.clip(0.5 + 0.5 * margin, 0.0, 1.0))
    if full_after > 0:
        c *= float(np.clip(duration / full_after, 0.0, 1.0)) ** 0.5
    return c


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[(first, end), ...] half-open runs of True in a 1-D bool array."""
    m = np.asarray(mask, dtype=bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], m.astype(np.int8), [0]])))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def clean_mask(mask: np.ndarray, fps: float, *, min_len: float, max_gap: float) -> np.ndarray:
    """A 1-D bool mask with gaps of at most ``max_gap`` s closed, then runs shorter than
    ``min_len`` s removed: a posture that flickers for a frame is one posture, and a blip
    of a frame is none."""
    m = np.asarray(mask, dtype=bool).copy()
    gap = int(round(max_gap * fps))
    if gap > 0:
        for a, b in runs(~m):
            if 0 < a and b < len(m) and b - a <= gap:
                m[a:b] = True
    shortest = max(1, int(round(min_len * fps)))
    for a, b in runs(m):
        if b - a < shortest:
            m[a:b] = False
    return m


def overlap(a: Finding, b: Finding) -> float:
    """Seconds that two findings share."""
    return max(0.0, min(a.end, b.end) - max(a.start, b.start))


def merge_series(found: list[Finding], gap: float = 1.5, label: str | None = None
                 ) -> list[Finding]:
    """Findings less than ``gap`` s apart (in time order) as one finding with their counts
    summed, spanning them all, at the largest confidence (``label``: the merged one's, else
    the first's): bowing again and again is one action, said with its count."""
    out: list[Finding] = []
    for f in sorted(found, key=lambda f: f.start):
        if out and f.start - out[-1].end < gap:
            g = out[-1]
            out[-1] = replace(g, label=label or g.label, end=max(g.end, f.end),
                              count=g.count + f.count, confidence=max(g.confidence,
                                                                      f.confidence))
        else:
            out.append(f)
    return out

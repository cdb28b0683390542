"""Does a generated motion perform the sentence's actions in the right order?

The check of the compositional-sentence criterion: the procedural corpus knows,
for each sample, its body primitives and their frame ranges. A generated motion of the
same sentence is cut at the same (time-rescaled) ranges, each segment gets the label of the
nearest *primitive prototype* (the mean descriptor of all training segments of that action),
and the order is right when the labels, with repeats merged, equal the ground truth's.

Only the ordered *body* primitives count ("walks, then turns, then squats"); upper-body
primitives layered on top of one ("waves while walking") happen at the same time, not in
sequence.

Descriptor of a segment (T, F) of per-frame features (normalised positions features work
well): per dimension the mean over time, the standard deviation over time and the mean
absolute frame-to-frame change, concatenated (3F,) — posture, range of motion and speed.
Pure numpy.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from motionlang.errors import MotionlangError


def segment_descriptor(x: np.ndarray) -> np.ndarray:
    """(T, F) segment -> (3F,) [mean, std, mean |diff|] over time (T >= 1)."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or len(x) == 0:
        raise MotionlangError(f"a segment must be (T >= 1, F), got {x.shape}")
    speed = np.abs(np.diff(x, axis=0)).mean(axis=0) if len(x) > 1 else np.zeros(x.shape[1])
    return np.concatenate([x.mean(axis=0), x.std(axis=0), speed])


@dataclass
class Prototypes:
    """Nearest-centroid classifier of segment descriptors.

    Attributes:
        labels: K action names. centroids: (K, 3F) mean descriptors.
        scale: (3F,) spread of the training descriptors, one value per block (mean, std,
            speed), so that no block dominates the distance by its range.
        examples, example_labels: the N training descriptors (N, 3F) and their labels, kept
            when fitted with ``nearest_example=True``: :meth:`label` then returns the label
            of the nearest training segment (1-NN) instead of the nearest centroid, which
            tells apart actions whose mean descriptors lie close (walk vs turn, kick vs
            stomp; figures in ``docs/results/twostream.md``, The order check).
    """

    labels: list[str]
    centroids: np.ndarray
    scale: np.ndarray
    examples: np.ndarray | None = None
    example_labels: list[str] | None = None

    @classmethod
    def fit(cls, segments: Iterable[tuple[str, np.ndarray]], nearest_example: bool = False
            ) -> Prototypes:
        """From (label, (T, F) segment) pairs of training motions."""
        by_label: dict[str, list[np.ndarray]] = {}
        for label, seg in segments:
            by_label.setdefault(str(label), []).append(segment_descriptor(seg))
        if not by_label:
            raise MotionlangError("no segments to build prototypes from")
        labels = sorted(by_label)
        allv = np.concatenate([np.stack(by_label[k]) for k in labels])
        # one scale per block (mean, std, speed), not per dimension: a per-dimension
        # z-score would blow up dimensions that barely vary (noise) to the size of the
        # informative ones; features are already normalised per dimension anyway
        spread = allv.std(axis=0).reshape(3, -1).mean(axis=1)
        scale = np.repeat(np.where(spread < 1e-8, 1.0, spread), allv.shape[1] // 3)
        centroids = np.stack([np.mean(by_label[k], axis=0) for k in labels])
        if not nearest_example:
            return cls(labels, centroids, scale)
        return cls(labels, centroids, scale, allv,
                   [k for k in labels for _ in by_label[k]])

    def label(self, seg: np.ndarray) -> str:
        """(T, F) segment -> label of the nearest centroid (or training example)."""
        ref = self.centroids if self.examples is None else self.examples
        d = np.linalg.norm((ref - segment_descriptor(seg)) / self.scale, axis=1)
        i = int(np.argmin(d))
        return self.labels[i] if self.examples is None else self.example_labels[i]


def rescale_ranges(ranges: Sequence[tuple[int, int]], src_frames: int, dst_frames: int
                   ) -> list[tuple[int, int]]:
    """Frame ranges [start, end) of a ``src_frames`` sequence -> the same fractions of a
    ``dst_frames`` one (another frame rate or a generated motion of another length); every
    range keeps at least one frame."""
    if src_frames < 1 or dst_frames < 1:
        raise MotionlangError("frame counts must be >= 1")
    out = []
    for s, e in ranges:
        a = min(int(round(s * dst_frames / src_frames)), dst_frames - 1)
        b = max(min(int(round(e * dst_frames / src_frames)), dst_frames), a + 1)
        out.append((a, b))
    return out


def segment_labels(x: np.ndarray, ranges: Sequence[tuple[int, int]],
                   prototypes: Prototypes) -> list[str]:
    """Label each range [start, end) of the (T, F) sequence ``x``."""
    return [prototypes.label(np.asarray(x)[s:e]) for s, e in ranges]


def merge_repeats(labels: Sequence[str]) -> list[str]:
    """["walk", "walk", "turn", "walk"] -> ["walk", "turn", "walk"]."""
    return [l for i, l in enumerate(labels) if i == 0 or l != labels[i - 1]]


def order_matches(predicted: Sequence[str], truth: Sequence[str]) -> bool:
    """True when the predicted labels, repeats merged, equal the truth's, repeats merged."""
    return merge_repeats(list(predicted)) == merge_repeats(list(truth))


def order_accuracy(predicted: Sequence[Sequence[str]], truth: Sequence[Sequence[str]]
                   ) -> float:
    """Fraction of items whose action order matches (:func:`order_matches`)."""
    if len(predicted) != len(truth) or not truth:
        raise MotionlangError(f"{len(predicted)} predictions for {len(truth)} items")
    return float(np.mean([order_matches(p, t) for p, t in zip(predicted, truth)]))


def segment_accuracy(predicted: Sequence[Sequence[str]], truth: Sequence[Sequence[str]]
                     ) -> tuple[float, float]:
    """Fraction of segments labelled right, (first segments, all later segments): where
    :func:`order_accuracy` is all or nothing per item, this shows how far into a
    sequence a model stays right (NaN when there are no later segments)."""
    if len(predicted) != len(truth) or not truth:
        raise MotionlangError(f"{len(predicted)} predictions for {len(truth)} items")
    first, later = [], []
    for p, t in zip(predicted, truth):
        if len(p) != len(t) or not t:
            raise MotionlangError(f"{len(p)} segment labels for {len(t)} segments")
        first.append(p[0] == t[0])
        later += [a == b for a, b in zip(p[1:], t[1:])]
    return float(np.mean(first)), float(np.mean(later)) if later else math.nan


def segment_tally(predicted: Sequence[Sequence[str]], truth: Sequence[Sequence[str]]
                  ) -> tuple[dict[tuple[str, str], list[int]], dict[tuple[str, str], int]]:
    """Per true action, where :func:`segment_accuracy` gives one figure for all.

    Returns:
        right: ``{(place, action): [labelled right, segments]}`` with place "first" or
            "later"; confusions: ``{(true action, label): count}`` of the wrong labels.
    """
    if len(predicted) != len(truth):
        raise MotionlangError(f"{len(predicted)} predictions for {len(truth)} items")
    right: dict[tuple[str, str], list[int]] = {}
    confusions: dict[tuple[str, str], int] = {}
    for p, t in zip(predicted, truth):
        if len(p) != len(t):
            raise MotionlangError(f"{len(p)} segment labels for {len(t)} segments")
        for k, (a, b) in enumerate(zip(t, p)):
            cell = right.setdefault(("first" if k == 0 else "later", a), [0, 0])
            cell[0] += a == b
            cell[1] += 1
            if a != b:
                confusions[a, b] = confusions.get((a, b), 0) + 1
    return right, confusions

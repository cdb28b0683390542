"""How one row of the text-to-motion table is scored: the test item, the metrics of motions
generated for it, and the table they make.

Shared by the comparison (:mod:`.compare`), its baselines (:mod:`.baselines`) and the oracle
(:mod:`.oracle`); it imports none of them, so each can import it.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from motionlang.evaluation.action_order import (
    Prototypes,
    merge_repeats,
    order_accuracy,
    segment_accuracy,
    segment_labels,
)
from motionlang.evaluation.metrics.motion import position_metrics_mm
from motionlang.features.positions import split_global


@dataclass
class T2MItem:
    """One test sentence. target: (T, 21, 3) metres, anchored. ranges: body-primitive frame
    ranges at 12.5 Hz; truth: their actions (empty when the record has no ground truth)."""

    id: str
    sentence: str
    target: np.ndarray
    ranges: list[tuple[int, int]] = field(default_factory=list)
    truth: list[str] = field(default_factory=list)

    @property
    def compositional(self) -> bool:
        return len(merge_repeats(self.truth)) >= 2


def positions_to_features(features, p21: np.ndarray) -> np.ndarray:
    """Global (T, 21, 3) -> the normalised (T, 66) positions features (as ``encode``);
    ``features`` is anything with the positions features' ``normalizer``."""
    local, v, dyaw, _ = split_global(np.asarray(p21, dtype=np.float64))
    raw = np.concatenate([local.reshape(len(p21), -1), v, dyaw[:, None]], axis=1)
    return features.normalizer.transform(raw)


def score_generated(gen: dict[str, np.ndarray], items: Sequence[T2MItem], features,
                    prototypes: Prototypes | None) -> dict:
    """``compare.evaluate_model``'s result for motions already generated, ``{id: (T, 21,
    3)}`` with T = the item's target length."""
    m = position_metrics_mm([gen[it.id] for it in items], [it.target for it in items])
    comp = [it for it in items if it.compositional] if prototypes is not None else []
    acc = first = later = math.nan
    if comp:
        pred = [segment_labels(positions_to_features(features, gen[it.id]), it.ranges,
                               prototypes) for it in comp]
        acc = order_accuracy(pred, [it.truth for it in comp])
        first, later = segment_accuracy(pred, [it.truth for it in comp])
    return {"ape_local": m["ape_local"], "ape_root": m["ape_root"],
            "ave_local": m["ave_local"], "ave_root": m["ave_root"],
            "order_accuracy": acc, "first_segment_accuracy": first,
            "later_segment_accuracy": later, "n_items": len(items), "n_compositional": len(comp),
            "generated": gen}


def markdown_table(results: dict[str, dict]) -> str:
    """One row per model: APE/AVE local and root (mm, mm^2), order accuracy, and the
    fraction of first / later segments of the compositional items labelled right."""
    lines = ["| model | APE local (mm) | APE root (mm) | AVE local (mm^2) | AVE root (mm^2) "
             "| order acc. | segments right (first / later) |", "|---|---|---|---|---|---|---|"]

    def frac(x):
        return "-" if x is None or math.isnan(x) else f"{x:.2f}"
    for name, r in results.items():
        acc = "-" if math.isnan(r["order_accuracy"]) else \
            f"{r['order_accuracy']:.2f} ({r['n_compositional']})"
        segs = f"{frac(r.get('first_segment_accuracy'))} / {frac(r.get('later_segment_accuracy'))}"
        lines.append(f"| {name} | {r['ape_local']:.1f} | {r['ape_root']:.1f} | "
                     f"{r['ave_local']:.1f} | {r['ave_root']:.1f} | {acc} | {segs} |")
    n = next(iter(results.values()))["n_items"] if results else 0
    return "\n".join(lines) + f"\n\n{n} test sentences; positions after undoing the " \
        "normalisation (not the authors' normalised units).\n"

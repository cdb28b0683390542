"""Why in-betweening keeps the draft that arrives closest, not the one whose feet slide least
by the foot-skating measure: a check of what each choice does to the measure and to
stricter versions of it.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_draft_choice.py MODEL GAP TAKES \\
        [--data ../shared/data/bandai]          # e.g. masked 2 60

For TAKES Bandai test takes (as ``masked_inbetween.py``: the middle GAP seconds cut), the
model's drafts (its default number) are each joined to the kept frames with their feet held
(``inbetween.join``); one is kept by the smallest arrival miss, by the smallest foot
skating over the gap (``features.foot_lock.slide_speed``: toes below 5 cm moving slower
than 1 m/s, the project's measure) or by the same with steps up to 3 m/s counted. Printed
per choice: the joint error in the gap (mm) and the kept motion's skating counted up to
1 m/s, 3 m/s and at any speed, beside the real takes'; and the largest toe step at the
gap's edges. A choice by the 1 m/s measure can prefer feet that drag faster than that.
Progress (a line a take) goes to standard error.
Non-commercial: Bandai data (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

#: the speeds up to which a low toe's step counts as a slide: the project's measure, a
#: stricter one, and any speed
CAPS = {"1 m/s": 1.0, "3 m/s": 3.0, "any": float("inf")}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("model")
    p.add_argument("gap", type=float, help="seconds")
    p.add_argument("takes", type=int)
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    args = p.parse_args()

    import numpy as np
    from masked_inbetween import gap_cases, test_takes  # the same takes (this folder)

    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.joint_map import TOES
    from motionlang.models.masked.inbetween import arrival_miss, gaps, join

    model, options, test, sentences = test_takes(args.model, args.data)
    fps = model.fps

    def skating(p21: np.ndarray, cap: float) -> float:
        return foot_skating(p21, fps, speed=cap)

    def over_gaps(joined: np.ndarray, keep: np.ndarray, cap: float) -> float:
        speeds = [skating(joined[max(a - 1, 0):b + 1], cap) for a, b in gaps(keep)]
        speeds = [v for v in speeds if np.isfinite(v)]
        return float(np.mean(speeds)) if speeds else float("inf")

    choices = {"arrival": None, "skating up to 1 m/s": 1.0, "skating up to 3 m/s": 3.0}
    rows: dict[str, dict[str, list[float]]] = {
        c: {k: [] for k in ("err", *CAPS, "edge")} for c in choices}
    real: dict[str, list[float]] = {k: [] for k in CAPS}
    cases = list(gap_cases(test, round(args.gap * fps), fps, args.takes, 0))
    for n, (i, p21, _, keep, span) in enumerate(cases, 1):
        print(f"take {n}/{len(cases)}", file=sys.stderr, flush=True)
        for k, cap in CAPS.items():
            real[k].append(skating(p21[span], cap))
        drafts = model.inbetween_drafts(sentences[i].text, p21, keep, seed=0, options=options)
        joined = [join(d, p21, keep, fps, foot_lock=True) for d in drafts]
        miss = [arrival_miss(d, p21, keep) for d in drafts]
        (a, b), = gaps(keep)
        for name, by in choices.items():
            k = int(np.argmin(miss)) if by is None else min(
                range(len(joined)), key=lambda q: (over_gaps(joined[q], keep, by), miss[q]))
            out, r = joined[k], rows[name]
            r["err"].append(1000 * np.linalg.norm(out[~keep] - p21[~keep], axis=-1).mean())
            for c, cap in CAPS.items():
                r[c].append(skating(out[span], cap))
            toes = out[[a - 1, a, b - 1, b]][:, list(TOES)][..., [0, 2]]
            r["edge"].append(float(np.linalg.norm(np.diff(toes, axis=0)[[0, 2]], axis=-1).max()))
    print(f"{len(real['any'])} Bandai test takes, {args.gap:g} s gaps, model {args.model}\n")
    print("| drafts kept by | joint error (mm) | skating, steps up to 1 m/s | up to 3 m/s | "
          "any | largest toe step at an edge (m) |")
    print("|---|---|---|---|---|---|")
    for name, r in rows.items():
        print(f"| {name} | {np.mean(r['err']):.1f} | " + " | ".join(
            f"{np.nanmean(r[c]):.3f}" for c in CAPS) + f" | {np.max(r['edge']):.2f} |")
    print("| (the real takes) | | " + " | ".join(f"{np.nanmean(real[c]):.3f}" for c in CAPS)
          + " | |")


if __name__ == "__main__":
    main()

"""Bones through a filled gap: does joining a masked model's draft to the kept frames keep
the body's proportions? Gaps in the middle of a take and gaps that reach its end.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_end_gaps.py --model masked \\
        [--data ../shared/data/bandai] [--takes 30] [--gap 2]

For ``--takes`` Bandai test takes (as ``masked_inbetween.py``), ``--gap`` seconds are
regenerated in the middle and, separately, at the end; the draft that arrives closest is
joined to the kept frames by ``inbetween.blend`` and by the blend of the thirteenth
session (an offset per joint, for a gap at an end the kept side's offset throughout:
``per_joint`` below). Printed per case and join: over the generated frames, the mean and
the largest deviation of the worst bone from the take's own mean bone lengths (m), beside
the draft's own. Progress (a line a take) goes to standard error. Non-commercial: Bandai
data (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def per_joint(generated, source, keep):
    """The thirteenth session's blend: each joint moved by its own offset, linearly between
    the sides, a one-sided gap by the one offset throughout."""
    import numpy as np

    from motionlang.models.masked.inbetween import gaps
    gen, src = np.asarray(generated, dtype=float), np.asarray(source, dtype=float)
    out = np.where(keep[:, None, None], src, gen)
    for a, b in gaps(keep):
        if a == 0 and b == len(keep):
            continue
        before = src[a - 1] - gen[a - 1] if a > 0 else src[b] - gen[b]
        after = src[b] - gen[b] if b < len(keep) else before
        w = ((np.arange(a, b) - (a - 1)) / (b - a + 1.0))[:, None, None]
        out[a:b] = gen[a:b] + (1 - w) * before + w * after
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", required=True)
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--takes", type=int, default=30)
    p.add_argument("--gap", type=float, default=2.0)
    args = p.parse_args()

    import numpy as np
    from masked_inbetween import gap_cases, test_takes  # the same takes (this folder)

    from motionlang.features.joint_map import bone_lengths21
    from motionlang.models.masked.inbetween import arrival_miss, blend

    model, options, test, sentences = test_takes(args.model, args.data)
    fps = model.fps
    n_gap = round(args.gap * fps)
    rows: dict[tuple[str, str], list[tuple[float, float]]] = {}
    cases = list(gap_cases(test, n_gap, fps, args.takes, 0))
    for case in ("middle", "end"):
        for n, (i, p21, _, keep, _) in enumerate(cases, 1):
            print(f"{case} gaps: take {n}/{len(cases)}", file=sys.stderr, flush=True)
            if case == "end":
                keep = np.ones(len(p21), dtype=bool)
                keep[-n_gap:] = False
            drafts = model.inbetween_drafts(sentences[i].text, p21, keep, options=options)
            draft = min(drafts, key=lambda d: arrival_miss(d, p21, keep))
            own = bone_lengths21(p21).mean(axis=0)
            for name, out in (("draft as decoded", draft), ("blend", blend(draft, p21, keep)),
                              ("per_joint", per_joint(draft, p21, keep))):
                worst = np.abs(bone_lengths21(out[~keep]) - own).max(axis=1)
                rows.setdefault((case, name), []).append((worst.mean(), worst.max()))
    print(f"{len(cases)} Bandai test takes, {args.gap:g} s gaps, model {args.model}\n")
    print("| gap | frames | worst bone off its length, mean (m) | largest (m) |")
    print("|---|---|---|---|")
    for (case, name), v in rows.items():
        a = np.array(v)
        print(f"| {case} | {name} | {a[:, 0].mean():.3f} | {a[:, 1].max():.3f} |")


if __name__ == "__main__":
    main()

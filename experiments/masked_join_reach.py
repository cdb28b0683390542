"""Why in-betweening's joined feet still slide, and how far past the leg's length a held
ankle may be (``models/masked/inbetween.JOIN_REACH``; docs/results/masked.md, fifth stage).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_join_reach.py --model masked \
        [--data /tmp/bandai] [--gap 2] [--limit 60] [--reach 1.0 1.02 1.05 1.1]

On the Bandai test takes of ``masked_inbetween.py`` (the middle ``--gap`` seconds cut, the
take's sentence, the model's drafts, the one arriving closest kept), the chosen draft's
feet locked and blended onto the kept frames as ``inbetween.join`` does; then

1. the contacts (``foot_lock.contacts``) that reach into the gap, before the second lock,
   by what the lock would do with them at reach 1.0: held, left because the toe would be
   pulled more than ``max_shift`` (a glide), or left because the held ankle would be out of
   the leg's reach (with how far out: the largest held-ankle-to-hip distance over the leg's
   length);
2. the join with both locks at each ``--reach``: joint error over the gap (mm), foot
   skating over the gap and a frame either side as the issue measures it (slides slower
   than 1 m/s) and counting slides up to 3 m/s (so that a choice that only pushed slides
   past 1 m/s would show), with the real takes' figures.

About 2 minutes with the defaults on one core. Non-commercial: Bandai data (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", required=True, help="a masked model (file, run folder or name)")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--gap", type=float, default=2.0, help="seconds cut from each take")
    p.add_argument("--limit", type=int, default=60)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--reach", type=float, nargs="+", default=[1.0, 1.02, 1.05, 1.1])
    args = p.parse_args()

    import numpy as np
    from masked_inbetween import gap_cases, test_takes

    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.foot_lock import LEGS, _held_at, contacts, lock_feet
    from motionlang.models.masked.inbetween import arrival_miss, blend

    model, options, test, sentences = test_takes(args.model, args.data)
    fps = model.fps
    cases = []
    for i, p21, _, keep, span in gap_cases(test, round(args.gap * fps), fps, args.limit,
                                           args.seed):
        drafts = model.inbetween_drafts(sentences[i].text, p21, keep, seed=args.seed,
                                        options=options)
        cases.append((p21, keep, span, min(drafts, key=lambda d: arrival_miss(d, p21, keep))))
        if len(cases) % 10 == 0:
            print(f"drafts of {len(cases)} takes", flush=True)
    print(f"{len(cases)} Bandai test takes, {args.gap:g} s gaps, {options.drafts} drafts\n")

    kinds: dict[str, list] = {"held": [], "glide (pull > max_shift)": [],
                              "out of the leg's reach": []}
    for p21, keep, span, best in cases:
        joined = blend(lock_feet(best, fps), p21, keep)
        for hip, knee, ankle, _, toe in LEGS:
            for a, b in contacts(joined[:, toe], fps):
                if b < span.start or a >= span.stop:
                    continue
                xz = joined[a:b + 1, toe, [0, 2]]
                pinned = keep[a:b + 1]
                pull = _held_at(xz, pinned if pinned.any() else None) - xz
                held = joined[a:b + 1, ankle].copy()
                held[:, [0, 2]] += pull
                leg = (np.linalg.norm(joined[a:b + 1, knee] - joined[a:b + 1, hip], axis=-1)
                       + np.linalg.norm(joined[a:b + 1, ankle] - joined[a:b + 1, knee],
                                        axis=-1))
                out = float((np.linalg.norm(held - joined[a:b + 1, hip], axis=-1) / leg).max())
                path = float(np.linalg.norm(np.diff(xz, axis=0), axis=-1).sum())
                kind = ("glide (pull > max_shift)" if np.linalg.norm(pull, axis=-1).max() > 0.15
                        else "out of the leg's reach" if out > 1.0 else "held")
                kinds[kind].append((b - a + 1, path, out))
    print("| contacts reaching into the gaps, at reach 1.0 | contacts | frames | toe's path "
          "(m) | held ankle's farthest, x the leg: median / largest |")
    print("|---|---|---|---|---|")
    for kind, rows in kinds.items():
        r = np.array(rows) if rows else np.zeros((0, 3))
        far = (f"{np.median(r[:, 2]):.3f} / {r[:, 2].max():.3f}" if len(r) else "-")
        print(f"| {kind} | {len(r)} | {int(r[:, 0].sum())} | {r[:, 1].sum():.2f} | {far} |")

    real = [foot_skating(p21[span], fps) for p21, _, span, _ in cases]
    real3 = [foot_skating(p21[span], fps, speed=3.0) for p21, _, span, _ in cases]
    print(f"\n| reach | joint error (mm) | skating (m/s) | x real ({np.nanmean(real):.3f}) | "
          f"slides up to 3 m/s (real {np.nanmean(real3):.3f}) |")
    print("|---|---|---|---|---|")
    for reach in args.reach:
        err, skate, skate3 = [], [], []
        for p21, keep, span, best in cases:
            joined = blend(lock_feet(best, fps, reach=reach), p21, keep)
            held = lock_feet(joined, fps, anchor=False, pinned=keep, reach=reach)
            out = np.where(keep[:, None, None], p21, held)
            err.append(1000 * np.linalg.norm(out[~keep] - p21[~keep], axis=-1).mean())
            skate.append(foot_skating(out[span], fps))
            skate3.append(foot_skating(out[span], fps, speed=3.0))
        print(f"| {reach:g} | {np.mean(err):.1f} | {np.nanmean(skate):.3f} | "
              f"{np.nanmean(skate) / np.nanmean(real):.2f} | {np.nanmean(skate3):.3f} |")


if __name__ == "__main__":
    main()

"""Where in-betweening's foot skating comes from: how far a masked model's drafts arrive from
the kept frames after a gap, and what choosing among more drafts does to it.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_drafts.py --model masked \\
        [--data /tmp/bandai] [--takes 30] [--gap 2] [--drafts 1 8 32] [--no-goal]

For ``--takes`` Bandai test takes (drawn with seed 0 among those long enough) the middle
``--gap`` seconds are regenerated from the take's sentence by
``MaskedModel.inbetween_drafts`` (a model with goals is told where the gap ends): N drafts
(seeds 0..N-1, drawn one at a time here, so the draws differ from ``inbetween``'s one
batch). The one with the smallest ``inbetween.arrival_miss`` is kept (``generate --keep``
keeps the one whose joined frames slide least, ``inbetween.choose``) and joined to the kept
frames as decoded (``inbetween.blend``) and with its feet held (``inbetween.join``). Prints,
per N: the mean arrival miss (m: the offset change that the blend spreads over the gap),
the joint error in the gap (mm) and the foot skating over the gap and a frame either side
(m/s), beside the real takes' skating there; and the same for the take's own tokens
decoded (what a generator that drew the true tokens would get). Progress (a line a take)
goes to standard error.
Non-commercial: Bandai data (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", required=True, help="a masked model (file or run folder)")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--takes", type=int, default=30)
    p.add_argument("--gap", type=float, default=2.0, help="seconds")
    p.add_argument("--drafts", type=int, nargs="+", default=[1, 8, 32])
    p.add_argument("--no-goal", action="store_true",
                   help="a model with goals (config.goal) told none: its goal projection "
                        "zeroed, so the same weights can be compared with and without")
    args = p.parse_args()

    from dataclasses import replace

    import numpy as np
    from masked_inbetween import gap_cases, test_takes  # the same takes (this folder)

    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.models.masked.inbetween import arrival_miss, blend, join

    model, options, test, sentences = test_takes(args.model, args.data)
    fps = model.fps
    if args.no_goal and model.generator.goal is not None:
        model.generator.goal.weight.data.zero_()
    most = max(args.drafts)
    rows = {n: {"miss": [], "err": [], "skate": [], "locked_err": [], "locked_skate": []}
            for n in args.drafts}
    real_skate = []
    oracle: dict[str, list] = {"miss": [], "err": [], "skate": []}
    cases = list(gap_cases(test, round(args.gap * fps), fps, args.takes, 0))
    for k, (i, p21, _, keep, span) in enumerate(cases, 1):
        print(f"take {k}/{len(cases)}", file=sys.stderr, flush=True)
        real_skate.append(foot_skating(p21[span], fps))
        drafts = [model.inbetween_drafts(sentences[i].text, p21, keep, seed=seed,
                                         options=replace(options, drafts=1))[0]
                  for seed in range(most)]
        misses = [arrival_miss(d, p21, keep) for d in drafts]
        # the floor: the take's own tokens through the decoder, placed the same way
        own = model.decode_placed(model.reconstruct(model.features.encode_positions(p21)),
                                  p21, keep)
        oracle["miss"].append(arrival_miss(own, p21, keep))
        out = blend(own, p21, keep)
        oracle["err"].append(1000 * np.linalg.norm(out[~keep] - p21[~keep], axis=-1).mean())
        oracle["skate"].append(foot_skating(out[span], fps))
        for n in args.drafts:
            k = int(np.argmin(misses[:n]))
            out, locked = blend(drafts[k], p21, keep), join(drafts[k], p21, keep, fps,
                                                            foot_lock=True)
            r = rows[n]
            r["miss"].append(misses[k])
            for tag, o in (("", out), ("locked_", locked)):
                r[tag + "err"].append(1000 * np.linalg.norm(o[~keep] - p21[~keep], axis=-1).mean())
                r[tag + "skate"].append(foot_skating(o[span], fps))
    print(f"{len(cases)} Bandai test takes, {args.gap:g} s gaps, model {args.model}\n")
    print("| drafts | arrival miss (m) | error (mm) | skating (m/s) | feet locked: error | "
          "skating | real takes' skating |")
    print("|---|---|---|---|---|---|---|")
    for n, r in rows.items():
        m = {k: float(np.nanmean(v)) for k, v in r.items()}
        print(f"| {n} | {m['miss']:.3f} | {m['err']:.1f} | {m['skate']:.3f} | "
              f"{m['locked_err']:.1f} | {m['locked_skate']:.3f} | "
              f"{np.nanmean(real_skate):.3f} |")
    m = {k: float(np.nanmean(v)) for k, v in oracle.items()}
    print(f"| the take's own tokens | {m['miss']:.3f} | {m['err']:.1f} | {m['skate']:.3f} | "
          f"| | {np.nanmean(real_skate):.3f} |")


if __name__ == "__main__":
    main()

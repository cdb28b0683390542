"""Where a text-to-motion model's foot skating comes from, and how far the foot lock can take
it (docs/results/real-motion.md, fifth session).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/skating_by_content.py [--model l2m]
        [--data ../shared/data/bandai] [--shifts 0.15 0.2 0.25 0.3 10] [--judge judge]

One motion per Bandai test take from its sentence (expected frames, the take's length, as
``motionlang evaluate-judge`` makes them). Prints the foot skating (``metrics.physics``) of
the real takes, of the decoded motions, of the locked ones without the lock's root step
(``anchor=False``) and with it (what ``generate`` writes) per asked content, then the mean
over all motions for each ``max_shift`` of ``features.foot_lock.lock_feet`` (the
farthest a held toe may be pulled; 0.15 m is the default, 10 m means no limit: only the leg's
reach then stops a hold), and how far the root travels (start to end, m) as decoded and as
written, since the root step changes it; last, the real takes themselves through
``lock_feet``: their skating, travel and how the packaged judge (``--judge``) recognises them
(their own labels) beside the takes as they are. Non-commercial: Bandai data and models
trained on it (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", default="l2m")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--shifts", type=float, nargs="+", default=[0.15, 0.2, 0.25, 0.3, 10.0])
    p.add_argument("--judge", default="judge")
    args = p.parse_args()

    import numpy as np
    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.foot_lock import lock_feet
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.t2m import FPS

    real = bandai_items(args.data, "test", fps=FPS)
    sentences = bandai_sentences(args.data, "test", seed=0)
    t2m = ml.text_to_motion(args.model)
    kw = {} if t2m.deterministic else {"method": "mean", "seed": 0}
    gen = [t2m.positions21(s.text, max(2, len(it.positions)), **kw)
           for s, it in zip(sentences, real)]

    def skating(motions) -> list[float]:
        return [foot_skating(m, FPS) for m in motions]

    columns = {"real": skating([it.positions for it in real]), "decoded": skating(gen),
               "lock only": skating([lock_feet(m, FPS, anchor=False) for m in gen]),
               "root step + lock": skating([lock_feet(m, FPS) for m in gen])}
    by: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    for i, it in enumerate(real):
        for name, values in columns.items():
            if np.isfinite(values[i]):
                by[it.content][name].append(values[i])
    print(f"{len(real)} Bandai test takes, model {args.model}: foot skating (m/s), mean over "
          "the motions with a contact\n")
    print("| asked content | motions | real takes | decoded | lock only | root step + lock |")
    print("|---|---|---|---|---|---|")
    for content in sorted(by):
        row = by[content]
        print(f"| {content} | {len(row['real'])} | " + " | ".join(
            f"{np.mean(row[k]):.3f}" for k in columns) + " |")
    print(f"| all | {len(real)} | " + " | ".join(
        f"{np.nanmean(columns[k]):.3f}" for k in columns) + " |\n")

    def travel(m) -> float:
        return float(np.linalg.norm(m[-1, 0, [0, 2]] - m[0, 0, [0, 2]]))

    locked_real = [lock_feet(it.positions, FPS) for it in real]
    moves = {"real": [travel(it.positions) for it in real], "decoded": [travel(m) for m in gen],
             "written": [travel(lock_feet(m, FPS)) for m in gen],
             "real locked": [travel(m) for m in locked_real]}
    print("| asked content | root travel (m): real takes | decoded | as written | real takes "
          "through the lock |")
    print("|---|---|---|---|---|")
    for content in sorted(by):
        rows = [i for i, it in enumerate(real) if it.content == content]
        print(f"| {content} | " + " | ".join(
            f"{np.mean([moves[k][i] for i in rows]):.2f}" for k in moves) + " |")
    print("| all | " + " | ".join(f"{np.mean(moves[k]):.2f}" for k in moves) + " |\n")
    print("| lock's max_shift (m) | foot skating (m/s) | times the real takes' |")
    print("|---|---|---|")
    truth = np.nanmean(columns["real"])
    for shift in args.shifts:
        v = np.nanmean(skating([lock_feet(m, FPS, max_shift=shift) for m in gen]))
        print(f"| {shift:g} | {v:.4f} | {v / truth:.2f} |")

    from motionlang.evaluation.judge import judge_table
    labels = [(it.content, it.style) for it in real]
    table = judge_table(ml.load_model(args.judge, kind="judge"), [it.positions for it in real],
                        labels, FPS, {"locked": locked_real}, labels, FPS)
    t, lk = table["ground truth"], table["locked"]
    print(f"\nThe real takes through the lock: skating {np.nanmean(skating(locked_real)):.3f} "
          f"m/s (as they are {truth:.3f}); judged {100 * lk['content_acc']:.1f} / "
          f"{100 * lk['style_acc']:.1f} % (as they are {100 * t['content_acc']:.1f} / "
          f"{100 * t['style_acc']:.1f} %), FID {lk['fid']:.3f} against the takes as they are")


if __name__ == "__main__":
    main()

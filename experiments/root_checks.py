"""The root's one-frame moves on the Bandai test takes, and where an L2M told its length ends
(docs/results/real-motion.md, ninth session).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/root_checks.py [--model l2m]
        [--model twostream] [--data ../shared/data/bandai]

1. For each L2M given: on how many test sentences its end flag stops it before the take's
   length when it is not held to it (``models.seq2seq.decode.search.generate``, mean decoding, the length
   given), and by how many frames at most.
2. For the real takes and each model's motions as ``generate`` writes them (held to the
   take's length, ``lock_feet``): how many motions change their one-frame root move by more
   than 10 cm and than the real takes' largest change (``metrics.physics.root_kick``), the
   largest change, and the largest one-frame root move (``root_jitter``).
Non-commercial: the Bandai data and the packaged models trained on it are CC BY-NC 4.0.
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", action="append", help="packaged name or file (repeat)")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    args = p.parse_args()

    import numpy as np
    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.evaluation.metrics.physics import root_jitter, root_kick
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.seq2seq.decode.search import generate
    from motionlang.models.t2m import FPS
    from motionlang.utils.progress import progress

    real = bandai_items(args.data, "test", fps=FPS)
    sentences = bandai_sentences(args.data, "test", seed=0)
    pairs = list(zip(sentences, real))
    motions = {"real takes": [it.positions for it in real]}
    for name in args.model or ["l2m", "twostream"]:
        t2m = ml.text_to_motion(name)
        model = t2m.model
        if model.kind == "l2m" and model.config.progress_input:
            short = []
            for s, it in progress(pairs, desc=f"{name}, own end", unit="motions"):
                frames, _ = generate(model, s.text, method="mean", n_frames=len(it.positions))[0]
                short.append(len(it.positions) - len(frames))
            short = np.array(short)
            print(f"{name}: its end flag stops it before the take's length on {(short > 0).sum()}"
                  f" of {len(short)} test sentences, at most {short.max()} frames early")
        kw = {} if t2m.deterministic else {"method": "mean", "seed": 0}
        motions[name] = [t2m.positions21(s.text, max(2, len(it.positions)), foot_lock=True, **kw)
                         for s, it in progress(pairs, desc=name, unit="motions")]
    largest = max(root_kick(m) for m in motions["real takes"])
    print(f"\n| {len(real)} Bandai test takes | root kick > 10 cm | > {100 * largest:.1f} cm "
          "(the real takes' largest) | largest root kick cm | largest root move cm |")
    print("|---|---|---|---|---|")
    for name, ms in motions.items():
        k = np.array([root_kick(m) for m in ms])
        j = max(root_jitter(m) for m in ms)
        print(f"| {name} | {(k > 0.10).sum()} | {(k > largest + 1e-9).sum()} | "
              f"{100 * k.max():.1f} | {100 * j:.1f} |")


if __name__ == "__main__":
    main()

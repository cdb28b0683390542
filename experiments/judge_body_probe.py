"""Why the first judge called the two-stream model's motions "run" (docs/results/real-motion.md,
fifth session): how far each body's hips sit from the root, in the judge's own features.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/judge_body_probe.py \
        [--data ../shared/data/bandai] [--model l2m --model twostream] [--sentences 20]

Prints the left hip's sideways offset in the body frame (``models.judge.model.position_rows``,
read as given, on each motion's own bones) over the Bandai training takes (mean and spread)
and over each model's motions for every 28th Bandai test sentence, and how many of the
training takes' standard deviations the models' mean lies from theirs. The judge packaged
since the fifth session lays every motion on one body first, where that offset is the same
for all. Non-commercial: Bandai data and models trained on it (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LEFT_HIP_X = 3 * 11   # column of joint 11 (LH, the left hip) x in the 66 position rows


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--model", action="append")
    p.add_argument("--sentences", type=int, default=20)
    args = p.parse_args()

    import numpy as np
    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.judge.model import position_rows
    from motionlang.models.t2m import FPS

    train = np.concatenate([position_rows(it.positions)[:, LEFT_HIP_X]
                            for it in bandai_items(args.data, "train", fps=FPS)])
    mean, std = float(train.mean()), float(train.std())
    print(f"Bandai training takes: left hip {100 * mean:.1f} cm from the root sideways, "
          f"spread {1000 * std:.1f} mm")
    real = bandai_items(args.data, "test", fps=FPS)
    sentences = bandai_sentences(args.data, "test", seed=0)
    step = max(1, len(real) // args.sentences)
    for name in args.model or ["l2m", "twostream"]:
        t2m = ml.text_to_motion(name)
        kw = {} if t2m.deterministic else {"method": "mean", "seed": 0}
        x = np.concatenate([position_rows(t2m.positions21(
            sentences[i].text, len(real[i].positions), **kw))[:, LEFT_HIP_X]
            for i in range(0, len(real), step)])
        print(f"{name}: left hip {100 * x.mean():.1f} cm (range {100 * x.min():.1f}-"
              f"{100 * x.max():.1f}), {abs(x.mean() - mean) / std:.0f} training standard "
              f"deviations from the takes'")


if __name__ == "__main__":
    main()

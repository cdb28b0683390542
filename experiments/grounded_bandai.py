"""What the gait check of ``describe`` does to the packaged M2L on its own test takes
(issue 41: "the packaged models keep >= 95 % of their figures").

    OMP_NUM_THREADS=1 .venv/bin/python experiments/grounded_bandai.py [--model m2l]
        [--bandai /tmp/bandai] [--limit N] [--every N]

For each of the 556 Bandai Namco test takes (dataset 2, take numbers 0 mod 5): the model's
first sentence as its beam ranks it (``describe --raw``) and as ``describe`` gives it
(checked against the gait, ``models.seq2seq.decode.grounded``); how often each names the take's action
and style (``evaluation.seq2seq.label_accuracy``, the figure of the README's table), and
every take where the two differ in the action they name.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="m2l")
    ap.add_argument("--bandai", default="/tmp/bandai")
    ap.add_argument("--limit", type=int, default=None)
    ap.add_argument("--every", type=int, default=1, help="every N-th test take (a sample)")
    args = ap.parse_args()

    import torch

    import motionlang as ml
    from motionlang.datasets.bandai import load_bandai
    from motionlang.datasets.bandai_text import names_content
    from motionlang.evaluation.seq2seq import label_accuracy
    torch.set_num_threads(1)
    model = ml.load_model(args.model)
    takes = load_bandai(args.bandai, split="test")[::args.every][:args.limit]
    texts: dict[str, dict[str, str]] = {"raw": {}, "grounded": {}}
    labels = {}
    for i, rec in enumerate(takes):
        motion = rec.load_motion()
        labels[rec.id] = rec.labels
        for mode in texts:
            texts[mode][rec.id] = ml.describe(motion, model, 5, raw=mode == "raw")[0][0]
        raw, grounded = texts["raw"][rec.id], texts["grounded"][rec.id]
        if names_content(raw, rec.content) != names_content(grounded, rec.content):
            print(f"{rec.id}: {raw!r} -> {grounded!r}", flush=True)
        if (i + 1) % 50 == 0:
            print(f"... {i + 1}/{len(takes)}", flush=True)
    for mode, t in texts.items():
        acc = label_accuracy(t, labels)
        print(f"{args.model} {mode:8s}: {acc['n']} takes, action {100 * acc['content']:.1f} %, "
              f"style {100 * acc['style']:.1f} %")


if __name__ == "__main__":
    main()

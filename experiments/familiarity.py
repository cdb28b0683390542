"""How familiar the packaged M2L is with motion from its own corpora and from another lab:
percentiles of ``models.seq2seq.decode.grounded.familiarity`` (RMS of its normalised input features) and
of its first sentence's log P per word, on Bandai test takes, ``cmu_dev`` files and
procedural samples (the figures ``FAMILIAR_RMS``, ``STYLE_RMS`` and ``LEAD_LOGP`` were set
from).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/familiarity.py --bandai /tmp/bandai \\
        --cmu-dev /tmp/cmu_dev/cmu-dev [--takes 40]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bandai", type=Path, required=True)
    ap.add_argument("--cmu-dev", type=Path, required=True)
    ap.add_argument("--takes", type=int, default=40, help="Bandai test takes (a sample)")
    args = ap.parse_args()
    import torch

    import motionlang as ml
    from motionlang.datasets.bandai import load_bandai
    from motionlang.datasets.synth import generate_sample
    from motionlang.features.frames import motion_frames
    from motionlang.models.seq2seq.decode.grounded import familiarity, per_word
    from motionlang.models.seq2seq.decode.search import _features_of
    torch.set_num_threads(1)
    model = ml.load_model("m2l")

    def measure(motion) -> tuple[float, float]:
        text, score = ml.describe(motion, model, 5, raw=True)[0]
        return familiarity(model, motion_frames(_features_of(model), motion, 1)[0]), \
            per_word(text, score)

    takes = load_bandai(args.bandai, split="test")
    pick = np.random.default_rng(0).choice(len(takes), min(args.takes, len(takes)),
                                           replace=False)
    sets = {f"{len(pick)} Bandai test takes": [takes[i].load_motion() for i in pick],
            "cmu_dev files": [ml.read_motion(p) for p in sorted(args.cmu_dev.glob("*/*.bvh"))],
            "20 procedural samples": [generate_sample(7, i).motion for i in range(20)]}
    print("| motion | familiarity 5 / 25 / 50 / 75 / 95th | log P per word 5 / 50 / 95th |")
    print("|---|---|---|")
    for name, motions in sets.items():
        got = np.array([measure(m) for m in motions])
        rms = " / ".join(f"{v:.2f}" for v in np.percentile(got[:, 0], [5, 25, 50, 75, 95]))
        lp = " / ".join(f"{v:.2f}" for v in np.percentile(got[:, 1], [5, 50, 95]))
        print(f"| {name} ({len(motions)}) | {rms} | {lp} |", flush=True)


if __name__ == "__main__":
    main()

"""Describe real CMU motions with M2L models and count how often the top description names
the action each trial shows (issue #24: "describe on real CMU files names a plausible action
for walks, runs and jumps").

    OMP_NUM_THREADS=1 .venv/bin/python experiments/describe_cmu.py [--model m2l ...]
        [--data ../shared/data] [-w 5]

Motions: the 33 trials of CMU subject 35 in ``cmu35/cmu35WalkJog.mat`` (Taylor 2006's data;
23 walks, 10 jogs at 30 Hz, labelled by ``datasets.named``), the raw ``cmu35/35_01.amc``
(a walk, 120 Hz) and the three raw ``cmu49`` trials (49_20: "a human balances on one foot";
49_18 and 49_19 have no annotation), printed for reading. The local data holds no real
jump: the jump criterion cannot be measured here. A walk counts as named when the top
description has a word of walking (walk, walks, walking, walked, strolls, steps), a jog
when it has one of running (run, runs, running, jog, jogs, jogging, dash, dashes, sprint).
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WORDS = {"walk": {"walk", "walks", "walking", "walked", "stroll", "strolls", "strolling",
                  "step", "steps"},
         "jog": {"run", "runs", "running", "ran", "jog", "jogs", "jogging", "dash", "dashes",
                 "dashing", "sprint", "sprints"}}


def named(text: str, label: str) -> bool:
    """Whether a description names the label's action (and not the other one)."""
    words = set(text.lower().split())
    other = "jog" if label == "walk" else "walk"
    return bool(words & WORDS[label]) and not words & WORDS[other]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", action="append", help="M2L models (default: the packaged m2l)")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("-w", "--width", type=int, default=5)
    args = ap.parse_args()

    import torch

    import motionlang as ml
    from motionlang.datasets.named import cmu35_walkjog
    torch.set_num_threads(1)
    data = Path(args.data)
    trials = cmu35_walkjog(data).trials
    raw = [data / "cmu35" / "35_01.amc"] + sorted((data / "cmu49").glob("*.amc"))
    for spec in args.model or ["m2l"]:
        model = ml.load_model(spec, kind="m2l")
        hits = {"walk": [0, 0], "jog": [0, 0]}
        print(f"== {spec}")
        for t in trials:
            text = ml.describe(t.motion, model, args.width)[0][0]
            ok = named(text, t.label)
            hits[t.label][0] += ok
            hits[t.label][1] += 1
            print(f"{t.trial} ({t.label}){'' if ok else ' MISSED'}: {text}")
        for path in raw:
            print(f"{path.name}: {ml.describe(path, model, args.width)[0][0]}")
        print(f"{spec}: walks named {hits['walk'][0]}/{hits['walk'][1]}, jogs named "
              f"{hits['jog'][0]}/{hits['jog'][1]}")


if __name__ == "__main__":
    main()

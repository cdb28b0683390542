"""Three joined takes written as BVH, to look at their timelines beside their renders
(issue 57): two of Bandai test takes (dataset 2), one of cmu_dev iClone walks and dribbles.
Prints each take's true spans.

    .venv/bin/python experiments/timelines_looked_at.py          # /tmp/tl0.bvh ... tl2.bvh
    motionlang describe /tmp/tl0.bvh --segments
    motionlang render /tmp/tl0.bvh /tmp/tl0.png --strip 10

Needs the Bandai archives extracted in /tmp/bandai and cmu_dev in /tmp/cmu_dev.
"""
from __future__ import annotations

import random
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "src"))

BANDAI_TAKES = (["walk", "wave-right-hand", "run", "raise-up-both-hands"],
                ["walk-turn-left", "raise-up-left-hand", "run"])


def main() -> None:
    from describe_timeline import cmu_dev_takes, join

    import motionlang as ml
    from motionlang.datasets.bandai import load_bandai
    rng = random.Random(5)
    test = [r for r in load_bandai("/tmp/bandai", "test") if r.dataset == 2]
    takes = []
    for contents in BANDAI_TAKES:
        picked = [rng.choice([r for r in test if r.content == c]) for c in contents]
        takes.append([(ml.read_motion(r.path), r.content) for r in picked])
    parts = cmu_dev_takes(Path("/tmp/cmu_dev/cmu-dev"), random.Random(1), 4)
    takes.append([(m, f"{name} ({verb})") for m, verb, name in parts])
    for n, take in enumerate(takes):
        ml.write_motion(join([m for m, _ in take]), f"/tmp/tl{n}.bvh")
        t = 0.0
        for m, label in take:
            print(f"tl{n}: {t:.1f}-{t + m.n_frames / m.fps:.1f} s  {label}")
            t += m.n_frames / m.fps


if __name__ == "__main__":
    main()

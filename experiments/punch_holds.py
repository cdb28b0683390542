"""How long the arm stays straight after each punch the analysis finds (what
``analysis.limbs.PUNCH_HOLD`` is set against): for every punch series of each file, the
spans (s) in which the arm is straighter than 0.8 of its length from the series' start on.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/punch_holds.py \\
        /tmp/bandai/Bandai-Namco-Research-Motiondataset-1/data/*punch*.bvh \\
        /work/extern/pybullet_data/data/motions/humanoid3d_punch.txt
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", type=Path)
    args = ap.parse_args()
    from motionlang.analysis.body import ARMS, Body
    from motionlang.analysis.limbs import PUNCH_FROM, punches
    from motionlang.errors import MotionlangError
    from motionlang.features.body21 import body21
    from motionlang.formats import read_motion
    warnings.simplefilter("ignore")
    for f in args.files:
        try:
            m = read_motion(f)
        except MotionlangError:
            continue
        b = Body.from_positions(body21(m), m.fps)
        for p in punches(b):
            s, _, w = ARMS[0 if p.side == "left" else 1]
            d = np.linalg.norm(b.p[:, w] - b.p[:, s], axis=1) / b.arm_length(
                0 if p.side == "left" else 1)
            straight = d > PUNCH_FROM + 0.1
            lo, hi = int(p.start * b.fps), min(b.n, int((p.end + 1.5) * b.fps))
            spans, k = [], lo
            while k < hi:
                if straight[k]:
                    j = k
                    while j < b.n and straight[j]:
                        j += 1
                    spans.append(round((j - k) / b.fps, 2))
                    k = j
                k += 1
            print(f"{f.parent.name}/{f.name}\t{p.side}\t{p.start:.2f}-{p.end:.2f} s\t"
                  f"{p.count} punches\tstraight spans (s): {spans}")


if __name__ == "__main__":
    main()

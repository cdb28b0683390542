"""How many frames the BVH reader leaves out at the start of each file as an exporter's
T-pose and its blend into the take (``kinematics.reference_pose``), counted by folder.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/reference_frames.py \\
        "/tmp/cmu_dev/cmu-dev/*/*.bvh" "/tmp/bandai/*/data/*.bvh"
"""
from __future__ import annotations

import argparse
import glob
import sys
import warnings
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("patterns", nargs="+", help="file patterns (quoted globs)")
    args = ap.parse_args()
    from motionlang.errors import MotionlangError
    from motionlang.formats import read_motion
    warnings.simplefilter("ignore")
    counts: Counter[tuple[str, int]] = Counter()
    for f in sorted(f for g in args.patterns for f in glob.glob(g)):
        try:
            m = read_motion(f)
        except MotionlangError:
            continue
        counts[(Path(f).parent.name, int(m.meta.get("reference_frames", 0)))] += 1
    print("folder\tframes left out\tfiles")
    for (folder, k), n in sorted(counts.items()):
        print(f"{folder}\t{k}\t{n}")


if __name__ == "__main__":
    main()

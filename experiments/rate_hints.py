"""How often ``analysis.rate.rate_hint`` speaks, on folders of takes whose rates are right
(and on ones known to be wrong): every motion file under each folder, the files it flags,
the count per folder, the time it took.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/rate_hints.py /tmp/lib [DIR ...]
"""
from __future__ import annotations

import argparse
import time
import warnings
from collections import Counter
from pathlib import Path

from motionlang.analysis.rate import rate_hint
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import positions21
from motionlang.formats import read_motion
from motionlang.library.scan import motion_files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folders", nargs="+", type=Path)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    for folder in args.folders:
        checked, flagged, rates = 0, [], Counter()
        t0 = time.perf_counter()
        for path in motion_files(folder):
            try:
                m = read_motion(path)
                p = positions21(m)
            except MotionlangError:
                continue
            checked += 1
            rates[round(m.fps)] += 1
            hint = rate_hint(p, m.fps)
            if hint is not None:
                flagged.append(hint.line(str(path.relative_to(folder))))
        print(f"{folder}: {checked} takes (rates {dict(rates)}), {len(flagged)} flagged, "
              f"{time.perf_counter() - t0:.0f} s")
        for line in flagged:
            print("  " + line)


if __name__ == "__main__":
    main()

"""Walks and runs with their travel taken out, as on a treadmill: what the analysis says of
each labelled take once its root is held over one spot (the steps stay), with the cadence
and the lower foot's flights it read the gait from.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/in_place.py \\
        "/tmp/bandai/Bandai-Namco-Research-Motiondataset-1/data/*_00[12].bvh" [MORE GLOBS]

Takes whose file name holds "walk" or "run" (Bandai's labels) are read; the others skipped.
Prints one line per take: the label, the sentence, and each in-place finding's steps,
cadence (steps a second) and flight rise (leg lengths). Bandai data: CC BY-NC.
"""
from __future__ import annotations

import argparse
import glob
import re
import warnings

from motionlang.analysis import analyse_positions, positions21
from motionlang.formats import read_motion


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("globs", nargs="+")
    args = ap.parse_args(argv)
    for path in sorted({p for g in args.globs for p in glob.glob(g)}):
        label = re.search(r"_(walk|run|dash)(?:-\w+)?_", path)
        if not label:
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            motion = read_motion(path)
        p = positions21(motion).copy()
        p[:, :, [0, 2]] -= p[:, :1, [0, 2]]   # the root over one spot, the body facing on
        a = analyse_positions(p, motion.fps)
        found = [f"{f.label} {f.detail['steps']} steps {f.detail['cadence']:.2f}/s rise "
                 f"{f.detail['flight_rise']:.3f}" for f in a.findings if f.detail.get("in_place")]
        print(f"{path.rsplit('/', 1)[-1]}\t{a.sentence()}\t{'; '.join(found)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

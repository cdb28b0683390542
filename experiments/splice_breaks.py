"""How far real, continuous takes break from a smooth path, against the splices of takes
joined end to end: the measurement behind ``analysis.body.SPLICE``.

For every file it prints nothing but counts; at the end: the largest break of each
continuous take away from its first and last three frames (the ten largest listed), how
many files ``analysis.body.pieces`` cuts (none should be), and the break at the splice of
each joined pair of ``cmu_dev`` trials (joined as ``benchmarks/describe_timeline.py`` joins
them).

Run: .venv/bin/python experiments/splice_breaks.py --cmu-dev /tmp/cmu_dev/cmu-dev
     [--bandai /tmp/bandai] [--bandai-files 200]
"""
from __future__ import annotations

import argparse
import random
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from describe_timeline import join  # noqa: E402

import motionlang as ml  # noqa: E402
from motionlang.analysis import positions21  # noqa: E402
from motionlang.analysis.body import pieces  # noqa: E402
from motionlang.features.body21 import leg_length21  # noqa: E402
from motionlang.features.joint_map import bone_lengths21  # noqa: E402

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
PAIRS = {"secondlife": ["13_42", "08_07", "13_11", "08_05", "12_01", "13_32", "08_02", "13_40"],
         "iclone": ["06_04", "06_02", "06_01", "06_09", "05_01"]}


def breaks(p: np.ndarray) -> np.ndarray:
    """(T-1,) the break of each frame step, leg lengths (as ``analysis.body.pieces``)."""
    leg = leg_length21(bone_lengths21(p))
    d = np.diff(p, axis=0)
    g = np.zeros(len(d))
    g[1:-1] = np.median(np.linalg.norm(d[1:-1] - 0.5 * (d[:-2] + d[2:]), axis=-1), axis=1)
    return g / leg


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cmu-dev", type=Path, required=True)
    ap.add_argument("--bandai", type=Path, default=None)
    ap.add_argument("--bandai-files", type=int, default=200)
    args = ap.parse_args()
    files = sorted(args.cmu_dev.glob("*/*.bvh")) + sorted(args.cmu_dev.glob("*/*.amc"))
    if args.bandai is not None:
        files += random.Random(0).sample(sorted(args.bandai.glob("*/data/*.bvh")),
                                         args.bandai_files)
    files += sorted(SHARED.glob("cmu49/**/*.amc")) + sorted(SHARED.glob("cmu35/**/*.amc"))
    worst, cut = [], 0
    for f in files:
        m = ml.read_motion(f)
        p = positions21(m)
        g = breaks(p)
        g[:3] = g[-3:] = 0
        i = int(g.argmax())
        worst.append((float(g[i]), f"{f.parent.name}/{f.name}", i / m.fps))
        cut += len(pieces(p, m.fps)) > 1
    worst.sort(reverse=True)
    print(f"{len(files)} continuous takes; cut by pieces(): {cut}; largest breaks:")
    for g, name, t in worst[:10]:
        print(f"  {g:.3f} L  {name} at {t:.2f} s")
    print("splices of joined cmu_dev trials:")
    for rig, names in PAIRS.items():
        for a, b in zip(names, names[1:]):
            ms = [ml.read_motion(args.cmu_dev / rig / f"{t}.bvh") for t in (a, b)]
            g = breaks(positions21(join(ms)))
            k = ms[0].n_frames - 1
            print(f"  {rig} {a} + {b}: {g[k - 1:k + 2].max():.3f} L")


if __name__ == "__main__":
    main()

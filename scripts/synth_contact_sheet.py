"""Contact sheet of random synthetic samples: one pose strip per sample, titled with
its first sentence, stacked into one PNG.

Usage: .venv/bin/python scripts/synth_contact_sheet.py OUT.png [--n 12] [--seed 0]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--n", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--corpus-size", type=int, default=5000,
                    help="draw sample indices from this many")
    args = ap.parse_args(argv)

    import imageio.v3 as iio

    from motionlang.datasets.synth.corpus import generate_sample
    from motionlang.rendering.strip import render_strip
    from motionlang.utils.atomic import atomic_path

    idx = np.random.default_rng(args.seed).choice(args.corpus_size, args.n, replace=False)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in sorted(idx.tolist()):
            s = generate_sample(0, i)
            path = Path(tmp) / f"{s.id}.png"
            render_strip(s.motion, path, n_frames=8, title=f"{s.id}: {s.annotations[0]}")
            rows.append(iio.imread(path)[..., :3])
            print(s.id, "|", " | ".join(s.annotations))
    width = max(r.shape[1] for r in rows)
    rows = [np.pad(r, ((0, 0), (0, width - r.shape[1]), (0, 0)), constant_values=255)
            for r in rows]
    with atomic_path(args.out) as tmp_path:
        iio.imwrite(tmp_path, np.concatenate(rows, axis=0))
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

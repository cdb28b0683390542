"""How long the grounded analysis (``motionlang.analysis``) takes on a long take: a 10-minute
120 Hz take (CMU 35_01 walked again and again, or a procedural walk where the shared data is
absent), medians of repeated runs on one thread.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_analysis.py [--minutes 10] [--repeat 3]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def long_take(minutes: float) -> tuple[np.ndarray, float]:
    """(T, 21, 3) positions of ``minutes`` of walking at 120 Hz, and the rate."""
    from motionlang.features.joint_map import positions21
    from motionlang.formats import read_motion
    amc = ROOT.parent / "shared" / "data" / "cmu35" / "35_01.amc"
    if amc.is_file():
        motion = read_motion(amc)
    else:
        from motionlang.datasets.synth import generate_sample
        motion = generate_sample(0, 0).motion
    p = positions21(motion)
    fps = float(motion.fps)
    n = int(minutes * 60 * fps)
    reps = -(-n // len(p))
    # each copy starts where the last one ended, so the take travels on
    step = p[-1, 0] - p[0, 0]
    step[1] = 0.0
    tiles = [p + k * step for k in range(reps)]
    return np.concatenate(tiles)[:n], fps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    from motionlang.analysis import analyse_positions
    p, fps = long_take(args.minutes)
    times = []
    for _ in range(args.repeat):
        t = time.perf_counter()
        a = analyse_positions(p, fps)
        times.append(time.perf_counter() - t)
    print(f"{len(p)} frames at {fps:g} Hz ({len(p) / fps / 60:.1f} min): analysis median "
          f"{statistics.median(times):.2f} s over {args.repeat} runs "
          f"(min {min(times):.2f}, max {max(times):.2f}); {len(a.findings)} findings, "
          f"{len(a.timeline())} timeline segments")


if __name__ == "__main__":
    main()

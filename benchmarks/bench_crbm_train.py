"""Time CRBM training at the paper's settings on CMU subject 35 (target: < 10 minutes).

200 hidden units, order 3, batch 100, 4000 passes over the 2,551 training positions of the
31 trials, with the selected settings (``crbm_reproduce.SELECTED``: weight decays, noise on
the past frames). Prints the median wall time of ``--repeats`` runs, the time per epoch, and the
1-minute load average before and after (other processes share the 2 cores).

    .venv/bin/python benchmarks/bench_crbm_train.py [--epochs 4000] [--repeats 1] [--save M.npz]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

from motionlang.evaluation.crbm.fill import load_cmu35
from motionlang.evaluation.crbm.reproduce import model_frames, selected_crbm_config
from motionlang.models.crbm.model import CRBM

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "cmu35"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--epochs", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--save", default=None, help="save the (last) trained model here")
    args = ap.parse_args()
    if not (DATA / "cmu35WalkJog.mat").exists():
        print(f"skipped: {DATA} not present")
        return 0
    seqs = [model_frames(c) for c in load_cmu35(DATA).train]
    times, model = [], None
    load0 = os.getloadavg()[0]
    for r in range(args.repeats):
        model = CRBM(selected_crbm_config(epochs=args.epochs, seed=r), 59)
        t0 = time.perf_counter()
        model.fit(seqs)
        times.append(time.perf_counter() - t0)
        print(f"run {r + 1}: {times[-1]:.1f} s", flush=True)
    med = statistics.median(times)
    print(f"CRBM train, 200 hidden, order 3, batch 100, history noise "
          f"{model.config.history_noise}, {args.epochs} epochs: median {med:.1f} s "
          f"({med / 60:.2f} min, {1000 * med / args.epochs:.1f} ms/epoch) over {args.repeats} run(s); "
          f"load average {load0:.2f} before, {os.getloadavg()[0]:.2f} after; "
          f"final reconstruction MSE {model.history[-1]:.4f}")
    if args.save:
        model.save(args.save)
    return 0


if __name__ == "__main__":
    sys.exit(main())

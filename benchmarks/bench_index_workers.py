"""``motionlang index --workers N`` against one process, on the same folder in the same run.

Each run builds the index of FOLDER anew (``rebuild``) into a temporary file, ``--repeat``
times per worker count, the counts interleaved so that a change in the machine's load falls
on both; prints each count's median seconds, files a second and its speed-up over one
process. Every run's worker processes load the model themselves (the start-up is counted:
a user pays it). Torch threads: ``--threads`` in all, split among the workers.

    .venv/bin/python benchmarks/bench_index_workers.py FOLDER [--workers 1 2] [--repeat 3]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="a folder of motion files")
    ap.add_argument("--model", default="retrieval", help="the model to embed with")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--threads", type=int, default=2, help="torch threads in all")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    import torch
    torch.set_num_threads(args.threads)
    import motionlang as ml
    seconds: dict[int, list[float]] = {w: [] for w in args.workers}
    files = 0
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeat):
            for w in args.workers:
                t0 = time.perf_counter()
                s = ml.index(args.folder, Path(tmp) / f"w{w}.idx", args.model, workers=w,
                             rebuild=True, show_progress=False)
                seconds[w].append(time.perf_counter() - t0)
                files = s.embedded
    base = statistics.median(seconds[args.workers[0]])
    print(f"{args.folder}: {files} files embedded each run, {args.repeat} runs per count, "
          f"{args.threads} torch threads in all, {os.cpu_count()} CPUs")
    for w, runs in seconds.items():
        med = statistics.median(runs)
        print(f"  workers {w}: median {med:.1f} s ({files / med:.1f} files/s), "
              f"x{base / med:.2f} against {args.workers[0]}; runs "
              + ", ".join(f"{r:.1f}" for r in runs))
    return 0


if __name__ == "__main__":
    sys.exit(main())

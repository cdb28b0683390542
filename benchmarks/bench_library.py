"""``motionlang index`` and ``search`` on a folder of motion files: how long they take and how
big the index is.

Prints: a first index of the folder (files/s, windows/s), a second run with nothing changed
(seconds: digests read, nothing embedded), a query with the model loaded (median of repeats
over a few sentences, ms; the first query, which loads the sentence encoder, is left out),
and the index's size per hour of motion. Any folder: e.g. the extracted Bandai archives or
``cmu-dev.tar.xz`` of ``../shared/data/cmu_dev`` extracted outside the repository.

    .venv/bin/python benchmarks/bench_library.py FOLDER [--model twostream] [--threads 1]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

QUERIES = ("a person walks forward", "someone jumps in place", "a person waves with the "
           "left hand", "someone dances", "a person dribbles a ball", "a person runs")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="a folder of motion files")
    ap.add_argument("--model", default="twostream", help="the model to embed with")
    ap.add_argument("--threads", type=int, default=1, help="torch and BLAS threads")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each query")
    ap.add_argument("--keep", default=None, help="keep the index in this file")
    args = ap.parse_args()
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(args.threads)
    import torch
    torch.set_num_threads(args.threads)
    import motionlang as ml
    from motionlang.library.embedder import Embedder
    from motionlang.library.search import Library

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.keep or Path(tmp) / "library.idx")
        t0 = time.perf_counter()
        embedder = Embedder.load(args.model)
        load_s = time.perf_counter() - t0
        first = ml.index(args.folder, out, embedder, rebuild=True)
        again = ml.index(args.folder, out, embedder)
        lib = Library.open(out, embedder)
        lib.search(QUERIES[0])   # loads the sentence encoder
        times = []
        for q in QUERIES:
            for _ in range(args.repeat):
                t = time.perf_counter()
                lib.search(q, k=10)
                times.append(time.perf_counter() - t)
        size = out.stat().st_size
    seen = first.files + len(first.failed)
    print(f"folder {args.folder}: {seen} motion files, {first.files} indexed, "
          f"{len(first.failed)} skipped; {first.takes} takes, {first.windows} windows, "
          f"{first.hours:.2f} h of motion; model {args.model} (loaded in {load_s:.1f} s), "
          f"{args.threads} thread(s)")
    print(f"index            {first.seconds:7.1f} s   {seen / first.seconds:6.1f} files/s   "
          f"{first.windows / first.seconds:6.1f} windows/s")
    print(f"re-index (same)  {again.seconds:7.2f} s   embedded {again.embedded} files")
    print(f"query            {1000 * statistics.median(times):7.1f} ms  median of "
          f"{len(times)} ({len(QUERIES)} sentences x {args.repeat}), k=10, model loaded")
    print(f"index size       {size / 2**20:7.2f} MiB  = {size / 2**20 / max(first.hours, 1e-9):.2f}"
          f" MiB per hour of motion")
    for path, why in first.failed:
        print(f"  skipped {path}: {why[:160]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

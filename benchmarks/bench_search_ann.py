"""Search of a very large index, exact (numpy) against approximate (usearch's HNSW graph):
query time, the graph's build and load time and size, and how many of the exact hits the
approximate search finds.

The index is synthetic, built here: ``--rows`` windows of ``--dim`` unit vectors drawn
around 2,000 centres (a library holds many alike windows: a walk's windows resemble one
another), 100 windows to a take. Queries: vectors near random windows. The query time is the
median of ``--queries`` queries through ``Library.rank`` (merging included; the sentence
encoder is not counted: its time is the same for both). ``--folder``: also index a real
folder once (rebuilt) and print the build time per 1,000 files.

    .venv/bin/python benchmarks/bench_search_ann.py [--rows 100000 1000000] [--folder DIR]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def synthetic(rows: int, dim: int, seed: int = 0):
    from motionlang.library.store import Entry, IndexData
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(2000, dim)).astype(np.float32)
    x = centres[rng.integers(0, len(centres), rows)] + 0.5 * rng.normal(
        size=(rows, dim)).astype(np.float32)
    per = 100
    takes = rows // per
    entries = [Entry(f"take_{i:06d}.bvh", 1, 0.0, "0" * 64, {}, 30.0, per + 2.0, per)
               for i in range(takes)]
    spans = np.tile(np.array([[s, s + 3.0] for s in range(per)], dtype=np.float64),
                    (takes, 1))
    return IndexData({"name": "synthetic", "digest": "s"}, "/", 3.0, 1.0, entries, [],
                     x[:takes * per], spans), rng


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[100_000])
    ap.add_argument("--dim", type=int, default=256)
    ap.add_argument("--queries", type=int, default=50)
    ap.add_argument("--k", type=int, default=10)
    ap.add_argument("--folder", help="a real folder to index once (time per 1,000 files)")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    import torch
    torch.set_num_threads(args.threads)
    import motionlang as ml
    from motionlang.library.embedder import Embedder
    from motionlang.library.search import Library
    from motionlang.library.store import save_index
    for rows in args.rows:
        data, rng = synthetic(rows, args.dim)
        with tempfile.TemporaryDirectory() as tmp:
            path = save_index(data, Path(tmp) / "synthetic.idx")
            emb = Embedder("synthetic", "s", lambda s: np.zeros(args.dim),
                           lambda m: np.zeros(args.dim))
            lib = Library.open(path, emb)
            qs = [data.vectors[i] + 0.3 * rng.normal(size=args.dim).astype(np.float32)
                  for i in rng.integers(0, len(data.vectors), args.queries)]
            t0 = time.perf_counter()
            lib.rank(qs[0], args.k, "usearch")
            build = time.perf_counter() - t0
            size = (Path(tmp) / "synthetic.idx.usearch").stat().st_size
            t0 = time.perf_counter()
            again = Library.open(path, emb)
            again.rank(qs[0], args.k, "usearch")
            load = time.perf_counter() - t0
            times: dict[str, list[float]] = {"numpy": [], "usearch": []}
            found = []
            for q in qs:
                got = {}
                for backend in times:
                    t0 = time.perf_counter()
                    got[backend] = again.rank(q, args.k, backend)
                    times[backend].append(time.perf_counter() - t0)
                exact = {h[:3] for h in got["numpy"]}
                found.append(len(exact & {h[:3] for h in got["usearch"]}) / max(1, len(exact)))
            idx_mb = Path(path).stat().st_size / 2**20
            print(f"{rows:,} windows x {args.dim} (index {idx_mb:.0f} MiB): query median "
                  f"exact {1e3 * statistics.median(times['numpy']):.1f} ms, approximate "
                  f"{1e3 * statistics.median(times['usearch']):.1f} ms; graph built in "
                  f"{build:.1f} s ({size / 2**20:.0f} MiB), loaded with the index in "
                  f"{load:.1f} s; exact hits found {100 * np.mean(found):.1f} %")
    if args.folder:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            s = ml.index(args.folder, Path(tmp) / "real.idx", show_progress=False)
            seconds = time.perf_counter() - t0
            print(f"{args.folder}: {s.files} files, {s.windows} windows indexed in "
                  f"{seconds:.1f} s: {1000 * seconds / max(1, s.files):.1f} s per 1,000 files, "
                  f"{Path(tmp, 'real.idx').stat().st_size / 2**20:.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())

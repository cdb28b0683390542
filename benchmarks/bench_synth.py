"""Time ``motionlang data synth`` (the corpus generator) and the per-sample parts.

Usage: .venv/bin/python benchmarks/bench_synth.py [--n 5000] [--workers 2] [--repeat 1]

Prints the wall time of writing N samples to a temporary folder (median of repeats), the
CPU time all processes spent on it, and the median per-sample time of generation alone
and of writing alone (1 process).
Target (issue 3): N = 5000 in under 120 s on 2 cores.
"""
from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    from motionlang.datasets.synth.corpus import generate_sample, write_corpus, write_sample

    with tempfile.TemporaryDirectory() as tmp:
        parts_gen, parts_write = [], []
        for i in range(50):
            t0 = time.perf_counter()
            s = generate_sample(args.seed, i)
            t1 = time.perf_counter()
            write_sample(s, tmp)
            parts_gen.append(t1 - t0)
            parts_write.append(time.perf_counter() - t1)
        print(f"per sample (1 process, median of 50): generate "
              f"{1000 * statistics.median(parts_gen):.1f} ms, write "
              f"{1000 * statistics.median(parts_write):.1f} ms")
        walls, cpus = [], []
        for r in range(args.repeat):
            out = Path(tmp) / f"run{r}"
            c0 = _cpu_seconds()
            t0 = time.perf_counter()
            write_corpus(out, args.n, args.seed, workers=args.workers)
            walls.append(time.perf_counter() - t0)
            cpus.append(_cpu_seconds() - c0)
            size = sum(p.stat().st_size for p in out.iterdir())
            shutil.rmtree(out)
        wall = statistics.median(walls)
        print(f"synth --n {args.n} --workers {args.workers}: median {wall:.1f} s over "
              f"{args.repeat} run(s) ({1000 * wall / args.n:.1f} ms/sample, "
              f"{size / 1e6:.0f} MB) -> {'OK' if wall < 120 * args.n / 5000 else 'SLOW'} "
              f"against 120 s per 5000")
        cpu = statistics.median(cpus)
        print(f"CPU time (all processes): {cpu:.1f} s = {1000 * cpu / args.n:.1f} ms/sample; "
              f"load average now {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs "
              f"(other work on the machine slows the wall time)")
    return 0


def _cpu_seconds() -> float:
    """User + system CPU seconds of this process and its finished children."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    sys.exit(main())

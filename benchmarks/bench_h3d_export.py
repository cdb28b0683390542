"""Time ``motionlang data export-h3d``: procedural motions to the HumanML3D layout.

Usage:
    .venv/bin/python benchmarks/bench_h3d_export.py [--n 300] [--body kit] [--mirror]
    .venv/bin/python benchmarks/bench_h3d_export.py --data /work/runs/corpus6000 [--limit 600]

Without ``--data``: N procedural motions (``datasets.synth``, 100 Hz MMM) made in memory
as they are exported; their generation time is measured apart and subtracted. With
``--data``: an existing corpus folder (anything ``load_records`` reads), its MMM files read
from disk as the real command does; ``--limit`` exports only its first motions.
Prints the time per motion and the extrapolation to 6,000 motions.
Target (issue, item 5): 6,000 procedural motions in under 5 minutes.
"""
from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

TARGET_N, TARGET_S = 6000, 300.0


class _Generated:
    """A record whose motion is generated on demand; generation time is added up."""

    spent = spent_cpu = 0.0

    def __init__(self, seed: int, index: int):
        self.seed, self.index = seed, index
        self.id = f"{index + 1:05d}"
        self.annotations: list[str] = []

    def load_motion(self):
        from motionlang.datasets.synth.corpus import generate_sample
        t0, c0 = time.perf_counter(), time.process_time()
        sample = generate_sample(self.seed, self.index)
        self.annotations = sample.annotations
        _Generated.spent += time.perf_counter() - t0
        _Generated.spent_cpu += time.process_time() - c0
        return sample.motion


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="a corpus folder to export (default: generate motions)")
    ap.add_argument("--n", type=int, default=300, help="motions to generate (default 300)")
    ap.add_argument("--limit", type=int, help="with --data: export only the first N motions")
    ap.add_argument("--body", choices=["kit", "smpl"], default="kit")
    ap.add_argument("--mirror", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    args = ap.parse_args(argv)

    from motionlang.datasets.humanml3d_export import export_h3d
    from motionlang.datasets.seq2seq_pairs import load_records

    t0 = time.perf_counter()
    if args.data:
        records = load_records(args.data, None)
        listed = len(records)
        records = records[:args.limit] if args.limit else records
    else:
        records = [_Generated(args.seed, i) for i in range(args.n)]
        listed = len(records)
    t_list = time.perf_counter() - t0
    with tempfile.TemporaryDirectory(prefix="bench_h3d_") as tmp:
        t0, c0 = time.perf_counter(), _cpu_seconds()
        info = export_h3d(records, Path(tmp) / "out", args.body, mirror=args.mirror,
                          workers=args.workers)
        wall, cpu = time.perf_counter() - t0, _cpu_seconds() - c0
    n = len(records)
    export_only = wall - _Generated.spent
    per = export_only / n
    total = per * TARGET_N + t_list * TARGET_N / max(listed, 1)
    source = args.data or f"{n} procedural motions made in memory" + (
        " (generation included: it runs in the worker processes)" if args.workers > 1 else "")
    print(f"export-h3d --body {args.body}{' --mirror' * args.mirror} --workers "
          f"{args.workers}: {source}")
    print(f"  listing {t_list:.1f} s for {listed} motions; export {wall:.1f} s for {n} "
          f"motions ({info['rows']} rows)" + (f", of which generation {_Generated.spent:.1f} s"
                                              if _Generated.spent else ""))
    print(f"  {1000 * per:.1f} ms per motion exported -> {TARGET_N} motions in about "
          f"{total:.0f} s (listing included): "
          f"{'OK' if total < TARGET_S else 'SLOW'} against {TARGET_S:.0f} s")
    cpu_per = (cpu - _Generated.spent_cpu) / n
    print(f"  CPU time {1000 * cpu_per:.1f} ms per motion (all processes) -> {TARGET_N} "
          f"motions in about {cpu_per * TARGET_N / max(1, args.workers):.0f} s on "
          f"{max(1, args.workers)} otherwise idle core(s)")
    print(f"  load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (other work on "
          "the machine slows the wall time)")
    return 0


def _cpu_seconds() -> float:
    """User + system CPU seconds of this process and its finished children."""
    me, kids = (resource.getrusage(resource.RUSAGE_SELF),
                resource.getrusage(resource.RUSAGE_CHILDREN))
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    sys.exit(main())

"""``describe DIR`` (one process, the model loaded once) against one ``describe FILE`` process
per file, on the same takes: Bandai Namco BVH takes chosen at random with a seed (the
archives extracted once into $MOTIONLANG_CACHE, outside the repository), linked into a
temporary folder.

Prints the median wall time of ``describe DIR -o captions.jsonl`` over ``--repeat`` runs
(with each ``--workers`` value asked for), the total and the median per file of the one-file
processes, their ratio, and whether both ways gave every file the same first sentence.

Run: .venv/bin/python benchmarks/bench_describe_many.py [--n 100] [--seed 0] [--repeat 3]
     [--workers 1 2]
"""
from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import need_data  # noqa: E402

from motionlang.datasets.bandai import load_bandai  # noqa: E402


def command() -> list[str]:
    """The ``motionlang`` console script beside this interpreter, else ``python -m``."""
    script = Path(sys.executable).parent / "motionlang"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "motionlang.cli.main"]


def timed(argv: list[str]) -> tuple[float, str]:
    t0 = time.perf_counter()
    res = subprocess.run(argv, capture_output=True, text=True)
    took = time.perf_counter() - t0
    if res.returncode != 0:
        sys.exit(f"{' '.join(argv)} failed ({res.returncode}):\n{res.stderr}")
    return took, res.stdout


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="Bandai takes (default 100)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the choice of takes")
    ap.add_argument("--repeat", type=int, default=3, help="runs of describe DIR (median)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1],
                    help="--workers values of describe DIR (default 1)")
    ap.add_argument("-w", "--width", type=int, default=5, help="beam width (default 5)")
    args = ap.parse_args()

    takes = random.Random(args.seed).sample(load_bandai(need_data("bandai")), args.n)
    tmp = Path(tempfile.mkdtemp(prefix="bench_describe_"))
    folder = tmp / "takes"
    folder.mkdir()
    for rec in takes:
        (folder / rec.path.name).symlink_to(rec.path)
    files = sorted(folder.iterdir())
    ml, width = command(), ["-w", str(args.width)]
    print(f"{len(files)} Bandai takes (seed {args.seed}), beam width {args.width}; load "
          f"average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")

    many: dict[int, float] = {}
    records: dict[str, dict] = {}
    for workers in args.workers:
        times = []
        for i in range(args.repeat):
            out = tmp / f"captions_{workers}_{i}.jsonl"
            took, _ = timed([*ml, "describe", str(folder), "-o", str(out), *width,
                             "--workers", str(workers)])
            times.append(took)
            records = {r["file"]: r for r in map(json.loads, out.read_text().splitlines())}
        many[workers] = statistics.median(times)
        print(f"describe DIR --workers {workers}: median {many[workers]:.1f} s of "
              f"{args.repeat} ({', '.join(f'{t:.1f}' for t in times)}), "
              f"{len(files) / many[workers]:.1f} files/s")

    per_file, same = [], 0
    for path in files:
        took, printed = timed([*ml, "describe", str(path), *width, "--json"])
        per_file.append(took)
        first = json.loads(printed)[0]["text"]
        same += records[str(path)].get("sentences", [{}])[0].get("text") == first
    total = sum(per_file)
    print(f"{len(files)} describe FILE processes: {total:.1f} s in all, median "
          f"{statistics.median(per_file):.2f} s a file")
    for workers, t in many.items():
        print(f"speed-up of describe DIR --workers {workers}: {total / t:.1f}x")
    print(f"same first sentence both ways: {same} of {len(files)}; load average "
          f"{os.getloadavg()[0]:.1f} at the end")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()

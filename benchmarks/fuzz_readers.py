"""Fuzz every reader: N inputs per format (MMM, ASF, AMC, BVH, MIT, H3D), each read in a
child process under a memory cap and a time limit (``benchmarks/fuzzing/``), and count
what became of them.

Inputs: random edits of seeds (hand-made files and real ones from ../shared/data cut to a
few frames; for H3D tiny HumanML3D-layout folders built in code) and, for a share of them,
files crafted to stress one reader (deep and wide skeletons, child-first bone lists, huge
frame declarations, encodings and DTDs, MAT fields of the wrong type; for H3D ``.npy``
headers with other dtypes and huge shapes, NaN data, broken caption spans and split files).
The bar: 0 crashes, 0 hangs, 0 uncaught exceptions, 0 invalid results.
Prints a table per format and the first few examples of each bad kind; exit status 1 if
there is any. Inputs are reproducible from ``--seed``; ``--keep DIR`` saves the bad ones.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/fuzz_readers.py [N] [--formats mit,bvh]
"""
from __future__ import annotations

import argparse
import os
import random
import statistics
import sys
import time
import zlib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DATA  # noqa: E402
from fuzzing import FORMATS, Sandbox, crafted, mutate, seeds  # noqa: E402
from fuzzing.sandbox import EXTENSIONS, KINDS  # noqa: E402

BAD = ("crash", "hang", "uncaught", "invalid")


def fuzz_format(fmt: str, n: int, args, sandbox: Sandbox) -> dict:
    rng = random.Random(args.seed * 1000 + zlib.crc32(fmt.encode()))
    bases = seeds(fmt, DATA if DATA.is_dir() else None)
    counts = dict.fromkeys(KINDS, 0)
    examples: dict[str, list[str]] = {k: [] for k in BAD}
    times = []
    t0 = time.perf_counter()
    for i in range(n):
        if rng.random() < args.crafted:
            data, skeleton = crafted(fmt, rng.randrange)
            how = "crafted"
        else:
            base, skeleton = bases[rng.randrange(len(bases))]
            data, how = mutate(base, rng.randrange, fmt), "mutated"
        out = sandbox.run(fmt, data, skeleton)
        counts[out.kind] += 1
        times.append(out.seconds)
        if out.kind in BAD and len(examples[out.kind]) < args.examples:
            examples[out.kind].append(f"#{i} ({how}, {len(data):,} bytes): {out.detail}")
            if args.keep:
                Path(args.keep).mkdir(parents=True, exist_ok=True)
                (Path(args.keep) / f"{fmt}-{out.kind}-{i}{EXTENSIONS[fmt]}").write_bytes(data)
        if (i + 1) % 500 == 0:
            print(f"  {fmt}: {i + 1}/{n} in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return {"counts": counts, "examples": examples, "seconds": time.perf_counter() - t0,
            "median_ms": 1000 * statistics.median(times), "seeds": len(bases)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("n", nargs="?", type=int, default=10_000, help="inputs per format")
    ap.add_argument("--formats", default=",".join(FORMATS),
                    help=f"comma-separated, of {','.join(FORMATS)} (any case)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--crafted", type=float, default=0.25, help="share of crafted inputs")
    ap.add_argument("--time-limit", type=float, default=20.0, help="seconds per input")
    ap.add_argument("--memory-mib", type=int, default=1024,
                    help="address space the child may add after start-up")
    ap.add_argument("--examples", type=int, default=3, help="examples shown per bad kind")
    ap.add_argument("--keep", help="folder to save the bad inputs in")
    args = ap.parse_args(argv)
    fmts = [f.strip().lower() for f in args.formats.split(",") if f.strip()]
    unknown = [f for f in fmts if f not in FORMATS]
    if unknown:
        ap.error(f"unknown format {unknown[0]!r} (choose from {', '.join(FORMATS)})")
    print(f"fuzzing {', '.join(fmts)}: {args.n:,} inputs each ({args.crafted:.0%} crafted), "
          f"seed {args.seed}, limits {args.time_limit:g} s and {args.memory_mib} MiB per "
          f"input, real seeds {'from ' + str(DATA) if DATA.is_dir() else 'absent'}")
    results = {}
    with Sandbox(memory_bytes=args.memory_mib << 20, time_limit=args.time_limit) as sandbox:
        for fmt in fmts:
            results[fmt] = fuzz_format(fmt, args.n, args, sandbox)
        restarts = sandbox.starts - 1
    cols = ("error", "valid") + BAD
    print(f"\n{'format':7}{'inputs':>8}" + "".join(f"{c:>10}" for c in cols)
          + f"{'seconds':>9}{'median ms':>11}")
    for fmt, r in results.items():
        c = r["counts"]
        print(f"{fmt:7}{sum(c.values()):>8}" + "".join(f"{c[k]:>10}" for k in cols)
              + f"{r['seconds']:>9.0f}{r['median_ms']:>11.1f}")
    print(f"(error = a clean one-line error naming the file; child restarts: {restarts})")
    bad = False
    for fmt, r in results.items():
        for kind, lines in r["examples"].items():
            if r["counts"][kind]:
                bad = True
                print(f"\n{fmt} {kind} ({r['counts'][kind]}):")
                for line in lines:
                    print(f"  {line}")
    return 1 if bad else 0


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    sys.exit(main())

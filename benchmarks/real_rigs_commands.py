"""Every command on real rigs: ``info``, ``render``, ``convert`` and ``describe`` (packaged
M2L, ``-w 5``) on BVH takes of both Bandai Namco archives chosen at random with a seed, and
on the CMU and KIT files of the shared data. Prints, per command, how many files failed
(exit code other than 0) and the first lines of each failure.

Run: .venv/bin/python benchmarks/real_rigs_commands.py [--n 100] [--seed 0] [--gif]
(the archives are extracted once into $MOTIONLANG_CACHE, default ~/.cache/motionlang)
"""
from __future__ import annotations

import argparse
import contextlib
import io
import random
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import need_data  # noqa: E402

from motionlang.cli.main import main as motionlang  # noqa: E402
from motionlang.datasets.bandai import load_bandai  # noqa: E402


def run(argv: list[str]) -> tuple[int, str]:
    """One command in this process: (exit code, what it printed)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            code = motionlang(argv)
        except SystemExit as exc:  # argparse
            code = exc.code if isinstance(exc.code, int) else 1
        except Exception as exc:  # noqa: BLE001 - a traceback is a failure we count
            code, _ = 99, out.write(f"{type(exc).__name__}: {exc}")
    return code, out.getvalue()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="Bandai takes tried (default 100)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--gif", action="store_true", help="render GIFs (default: PNG strips)")
    args = ap.parse_args()
    takes = load_bandai(need_data("bandai"))
    files = [str(r.path) for r in random.Random(args.seed).sample(takes, args.n)]
    files += [str(need_data(p)) for p in ("cmu35/35_01.amc", "cmu49/49_20.amc",
                                          "kitml/00001_mmm.xml")]
    tmp = Path(tempfile.mkdtemp(prefix="real_rigs_"))
    commands = {
        "info": lambda f, i: ["info", f],
        "render": lambda f, i: ["render", f, str(tmp / f"r{i}.{'gif' if args.gif else 'png'}")],
        "convert": lambda f, i: ["convert", f, str(tmp / f"c{i}.bvh")],
        "describe": lambda f, i: ["describe", f, "-w", "5"],
    }
    print(f"{args.n} Bandai takes (seed {args.seed}) + CMU 35_01, 49_20 + KIT 00001")
    for name, argv in commands.items():
        t0, failures, first = time.perf_counter(), [], {}
        for i, f in enumerate(files):
            code, text = run(argv(f, i))
            if code != 0:
                failures.append(f)
                first.setdefault(f, text.strip().splitlines()[-1:] or [f"exit {code}"])
            elif name == "describe" and i in (0, len(files) - 3, len(files) - 2, len(files) - 1):
                print(f"  {Path(f).name}: {text.splitlines()[0].strip()}")
        dt = time.perf_counter() - t0
        print(f"{name:9s} {len(failures):3d} of {len(files)} failed  ({dt / len(files):.2f} s "
              "per file)")
        for f, lines in list(first.items())[:5]:
            print(f"    {Path(f).name}: {lines[0][:200]}")


if __name__ == "__main__":
    main()

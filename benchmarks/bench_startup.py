"""How long one ``motionlang describe FILE`` process takes against ``python -c "import
torch"`` in the same run (issue 58: at most 1.6x), medians of repeated runs on one core, and
whether ``torch._dynamo`` is imported by ``describe``, ``generate`` (each packaged
text-to-motion family) and ``search`` (with a word its model knows and one it never saw); also ``motionlang -h``
and ``motionlang info FILE``, which load no model, against ``python -c "import numpy"``.

    .venv/bin/python benchmarks/bench_startup.py [--repeat 5] [FILE]

FILE defaults to a procedural motion written to a temporary folder.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
BIN = Path(sys.executable).parent


def timed(cmd: list[str], env: dict) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def imports_dynamo(cmd: list[str], env: dict) -> bool:
    run = subprocess.run([sys.executable, "-X", "importtime", "-m", "motionlang.cli.main",
                          *cmd], env=env, capture_output=True, text=True)
    return "torch._dynamo" in run.stderr


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("file", nargs="?", default=None)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    with tempfile.TemporaryDirectory() as tmp:
        path = args.file
        if path is None:
            import motionlang as ml
            from motionlang.datasets.synth import generate_sample
            path = str(Path(tmp) / "walk.bvh")
            ml.write_motion(generate_sample(0, 0).motion, path)
        torch_s, describe_s, numpy_s, help_s, info_s = [], [], [], [], []
        for _ in range(args.repeat):
            torch_s.append(timed([sys.executable, "-c", "import torch"], env))
            describe_s.append(timed([str(BIN / "motionlang"), "describe", path], env))
            numpy_s.append(timed([sys.executable, "-c", "import numpy"], env))
            help_s.append(timed([str(BIN / "motionlang"), "-h"], env))
            info_s.append(timed([str(BIN / "motionlang"), "info", path], env))
        n = statistics.median(numpy_s)
        print(f"python -c 'import numpy': median {n:.2f} s; motionlang -h: median "
              f"{statistics.median(help_s):.2f} s; motionlang info: median "
              f"{statistics.median(info_s):.2f} s")
        t, d = statistics.median(torch_s), statistics.median(describe_s)
        print(f"python -c 'import torch': median {t:.2f} s; motionlang describe: median "
              f"{d:.2f} s; ratio {d / t:.2f} (bar 1.6) over {args.repeat} runs each")
        gen = ["generate", "a person strolls", "-o", str(Path(tmp) / "g.bvh")]
        index = str(Path(tmp) / "lib.idx")
        subprocess.run([str(BIN / "motionlang"), "index", str(Path(path).parent), "-o", index],
                       check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for name, cmd in (("describe", ["describe", path]), ("generate (l2m)", gen),
                          ("generate --model twostream", [*gen, "--model", "twostream"]),
                          ("generate --model masked", [*gen, "--model", "masked"]),
                          ("search (a word of its vocabulary)",
                           ["search", "a person walks", "--index", index]),
                          ("search (a word it never saw)",
                           ["search", "a person strolls", "--index", index])):
            print(f"{name} imports torch._dynamo: {imports_dynamo(cmd, env)}")


if __name__ == "__main__":
    main()

"""What it costs to read the MIT ``motion.mat`` without risking the process.

scipy's MAT reader can be killed by a crafted file (SIGSEGV on a wrong type byte), so
``formats.mit`` reads through ``formats.matfile``, a strict pure numpy reader. The other way
out was scipy in a child process. This prints, on one core, the median of 7 runs of:

* ``matfile.read_mat`` (what ``read_mit`` uses) and the whole ``read_mit``;
* scipy's ``loadmat`` in this process (fast, but a bad file kills the caller);
* scipy's ``loadmat`` in a fresh child process that returns the arrays (what isolation
  would cost: a Python start, the scipy import, the arrays sent back).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mit_read.py
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import subprocess  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import median_time, need_data  # noqa: E402

from motionlang.formats.matfile import read_mat  # noqa: E402
from motionlang.formats.mit import read_mit  # noqa: E402

CHILD = ("import io, sys, numpy as np\nfrom scipy.io import loadmat\n"
         "d = loadmat(sys.argv[1])\nbuf = io.BytesIO()\n"
         "np.savez(buf, *[np.asarray(s, float) for s in d['Motion'].ravel()])\n"
         "sys.stdout.buffer.write(buf.getvalue())\n")


def main() -> None:
    from scipy.io import loadmat

    path = need_data("mit/motion.mat")
    print(f"{path} ({path.stat().st_size / 1e6:.2f} MB, compressed MAT v5)")
    rows = [("matfile.read_mat (pure numpy, strict)", lambda: read_mat(path)),
            ("read_mit (read_mat + checks + 3 Motions)", lambda: read_mit(path)),
            ("scipy loadmat in this process (unsafe)", lambda: loadmat(str(path))),
            ("scipy loadmat in a child process", lambda: subprocess.run(
                [sys.executable, "-c", CHILD, str(path)], capture_output=True, check=True))]
    for name, fn in rows:
        print(f"{name:44} {1000 * median_time(fn, repeat=7):8.1f} ms")


if __name__ == "__main__":
    main()

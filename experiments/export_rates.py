"""One export, one rate (``library/rates.py``), measured: the BVH files of a folder whose
true rate is known are copied with their headers rewritten to declare ``--declare`` Hz
(MakeHuman's BVH of CMU trials declare 25 Hz for 120 Hz frames), then read as a user would:
``describe DIR``'s shared rates, each file on its own (``at_export_rate``, as ``describe
FILE``, ``check``, ``info``, ``ml.describe(path)`` read it), and whether ``ml.describe``'s
first sentence names the same first action as for the file at its true rate.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/export_rates.py \\
        /tmp/cmu_dev/cmu-dev/secondlife --declare 25
"""
from __future__ import annotations

import argparse
import re
import tempfile
import warnings
from collections import Counter
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", type=Path, help="BVH files at their true rate")
    ap.add_argument("--declare", type=float, default=25.0, metavar="HZ")
    args = ap.parse_args()
    import torch

    import motionlang as ml
    from motionlang.analysis.words import actions_named
    from motionlang.formats import read_motion
    from motionlang.library.rates import at_export_rate, shared_rates
    torch.set_num_threads(1)
    warnings.simplefilter("ignore")
    model = ml.load_model("m2l")
    files = sorted(args.folder.glob("*.bvh"))
    with tempfile.TemporaryDirectory() as tmp:
        fake = []
        for f in files:
            text = re.sub(r"(?m)^Frame Time:.*$", f"Frame Time: {1.0 / args.declare:.8f}",
                          f.read_text())
            fake.append(Path(tmp) / f.name)
            fake[-1].write_text(text)
        shared = shared_rates(fake, show_progress=False)
        print(f"describe DIR: {sum(v is not None for v in shared.values())} of {len(fake)} "
              f"read at an export's rate "
              f"{dict(Counter(v.rate for v in shared.values() if v is not None))}")
        rates: Counter = Counter()
        same = 0
        for f, true in zip(fake, files):
            rates[at_export_rate(read_motion(f), f).fps] += 1
            first = (actions_named(ml.describe(f, model)[0][0]) or [None])[0]
            truth = (actions_named(ml.describe(true, model)[0][0]) or [None])[0]
            same += first == truth
            if first != truth:
                print(f"  {f.name}: {first} (at its true rate: {truth})")
        print(f"each file on its own, read at: {dict(rates)}; describe's first action as at "
              f"the true rate: {same} of {len(files)}")


if __name__ == "__main__":
    main()

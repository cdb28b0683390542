"""How often ``analysis.rate.rate_hint`` speaks, on folders of takes whose rates are right
(and on ones known to be wrong): every motion file under each folder, the files it flags,
the count per folder, the time it took. With ``--declare HZ``, each take whose rate is above
it is also read as if its header declared HZ (MakeHuman's BVH of CMU trials declare 25 Hz
for 120 Hz frames): which rate the evidence names (steps or flights) against the true one,
and with ``--describe`` whether ``describe``'s first sentence names the same first action
as at the true rate once the take is read at the rate named (``analysis.rate.at_its_rate``,
as every command reads a file).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/rate_hints.py /tmp/lib [DIR ...]
    OMP_NUM_THREADS=1 .venv/bin/python experiments/rate_hints.py --declare 25 --describe \
        /tmp/cmu_dev/cmu-dev/secondlife
"""
from __future__ import annotations

import argparse
import time
import warnings
from collections import Counter
from pathlib import Path

from motionlang.analysis.rate import at_its_rate, rate_hint
from motionlang.analysis.words import actions_named
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import positions21
from motionlang.formats import read_motion
from motionlang.library.scan import motion_files


def _first_action(motion, model) -> str | None:
    import motionlang as ml
    found = actions_named(ml.describe(motion, model, width=4)[0][0])
    return found[0] if found else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--declare", type=float, default=None, metavar="HZ",
                    help="also read each faster take as if its header said HZ")
    ap.add_argument("--describe", action="store_true",
                    help="with --declare: compare describe's first action at both rates")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    model = None
    if args.describe:
        import torch

        import motionlang as ml
        torch.set_num_threads(1)
        model = ml.load_model("m2l")
    for folder in args.folders:
        checked, flagged, rates = 0, [], Counter()
        named: Counter = Counter()
        same = compared = 0
        t0 = time.perf_counter()
        for path in motion_files(folder):
            try:
                m = read_motion(path)
                p = positions21(m)
            except MotionlangError:
                continue
            checked += 1
            rates[round(m.fps)] += 1
            hint = rate_hint(p, m.fps)
            if hint is not None:
                flagged.append(hint.line(str(path.relative_to(folder))))
            if args.declare is None or m.fps <= args.declare:
                continue
            wrong = rate_hint(p, args.declare)
            how = "nothing" if wrong is None else "steps" if wrong.cadences else "flights"
            named[(round(m.fps), how, wrong and wrong.rate)] += 1
            if model is not None:
                at = at_its_rate(m.replace(fps=args.declare), str(path))
                one, two = _first_action(m, model), _first_action(at, model)
                compared += 1
                same += one == two
                print(f"  {path.relative_to(folder)}: {one} at {m.fps:g} Hz, {two} declared "
                      f"{args.declare:g} and read at {at.fps:g} Hz")
        print(f"{folder}: {checked} takes (rates {dict(rates)}), {len(flagged)} flagged, "
              f"{time.perf_counter() - t0:.0f} s")
        for line in flagged:
            print("  " + line)
        for (true, how, rate), n in sorted(named.items(), key=str):
            print(f"  true {true} Hz declared {args.declare:g}: {how} -> {rate} Hz: {n}")
        if compared:
            print(f"  same first action at both rates: {same} of {compared}")


if __name__ == "__main__":
    main()

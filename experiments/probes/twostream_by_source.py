"""Does a normaliser per source give the mixed two-stream model its Bandai figures back? The
package's recipe (procedural corpus + Bandai takes, half of every epoch each, mirrored),
each source's motions z-normalised with the mean and spread of that source's own training
motions (``train twostream --normalise by-source``: ``datasets.twostream_items.
normalise_by_source``); the model keeps the Bandai normaliser (the last source), so its
motions come out in the Bandai takes' statistics. Every epoch is scored on the Bandai
validation pairs (``--select-evaluator``).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_by_source.py RUN \
        --corpus runs/twostream_parts/corpus --evaluator runs/evaluator_bandai [--epochs 3]

Why: the mix's one normaliser has the spread of the procedural bodies (many sizes), several
times the Bandai takes' in the joints' heights, so a Bandai motion's vertical movement
weighs a fraction as much in the squared loss as it does when the model is trained on the
Bandai takes alone, which meets the evaluator's bars (``docs/results/twostream.md``).
Fitting one normaliser on the Bandai takes alone was the wrong test (the procedural heights
then span tens of units and dominate the loss: ``twostream_normaliser.py``).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--corpus", required=True, help="the procedural corpus (6,000, seed 0)")
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--evaluator", required=True)
    ap.add_argument("--epochs", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    import torch

    import motionlang as ml
    from motionlang.errors import MotionlangError
    sys.path.insert(0, str(ROOT / "experiments"))
    from twostream_parts import RECIPE
    torch.set_num_threads(a.threads)
    bandai = f"bandai:{a.bandai}"
    try:
        resume = (a.run / "last.pt").is_file()
        model = ml.train("twostream", [f"{a.corpus}@1", f"{bandai}@1"], a.run, resume=resume,
                         epochs=a.epochs, mirror=True, select_evaluator=a.evaluator,
                         select_data=bandai, normalise="by-source", **RECIPE)
    except MotionlangError as exc:
        print(f"twostream_by_source.py: {exc}", file=sys.stderr)
        return 2
    print(model)
    return 0


if __name__ == "__main__":
    sys.exit(main())

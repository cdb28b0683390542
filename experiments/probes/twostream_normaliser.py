"""Does the mix's feature normaliser cost the two-stream model its Bandai figures? The
package's recipe (procedural corpus + Bandai takes, half of every epoch each, mirrored)
trained with the normaliser fitted on the Bandai training takes alone instead of on both,
every epoch scored on the Bandai validation pairs (``--select-evaluator``).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_normaliser.py RUN \
        --corpus runs/twostream_parts/corpus --evaluator runs/evaluator_bandai [--epochs 3]

Why: the procedural corpus has bodies of many sizes, the Bandai actors nearly one, so the
mix's spread of the joints' heights is about 4 times the Bandai takes' and a Bandai
motion's vertical movement weighs a quarter as much in the loss
(``docs/results/twostream.md``, the ablations on real motion). Records that name their own
split (the Bandai takes) are the ones the normaliser is fitted on.
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
    import motionlang.datasets.twostream_items as items
    from motionlang.errors import MotionlangError
    sys.path.insert(0, str(ROOT / "experiments"))
    from twostream_parts import RECIPE
    torch.set_num_threads(a.threads)
    fitted = items.dataset_features

    def bandai_fit(records, *args, fit_records=None, **kw):
        own = [r for r in fit_records or [] if getattr(r, "split", None)]
        return fitted(records, *args, fit_records=own or fit_records, **kw)

    items.dataset_features = bandai_fit
    bandai = f"bandai:{a.bandai}"
    try:
        resume = (a.run / "last.pt").is_file()
        model = ml.train("twostream", [f"{a.corpus}@1", f"{bandai}@1"], a.run, resume=resume,
                         epochs=a.epochs, mirror=True, select_evaluator=a.evaluator,
                         select_data=bandai, **RECIPE)
    except MotionlangError as exc:
        print(f"twostream_normaliser.py: {exc}", file=sys.stderr)
        return 2
    print(model)
    return 0


if __name__ == "__main__":
    sys.exit(main())

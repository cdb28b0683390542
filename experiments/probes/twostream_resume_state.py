"""Resume a saved two-stream recipe state (``experiments/twostream_parts.py``) into a run
folder of its own with other options: what one more epoch does from a chosen epoch.

    git show a77b4ea:experiments/state/twostream_recipe/...   # the epoch-4 state, into STATE
    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_resume_state.py STATE RUN \
        --epochs 5 [--decay-epochs 1] [--weight adversarial=0.01]

Trains with the recipe's options (``twostream_parts.RECIPE``; the data and ``mirror`` as
the state was saved) to ``--epochs``, the run folder's ``last.pt``
first restored from STATE (a second call continues the run folder). Writes ``RUN/model.pt``;
score it with ``evaluation.t2m.selection.guo_selector`` or ``evaluate-t2m``. Run from the
project root: the state's data paths are relative to it.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))   # experiments.lab


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("state", type=Path)
    ap.add_argument("run", type=Path)
    ap.add_argument("--epochs", type=int, required=True)
    ap.add_argument("--decay-epochs", type=float, default=0.0)
    ap.add_argument("--weight", action="append", default=[], metavar="TERM=W",
                    help="a loss weight beside the recipe's (repeatable)")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    import torch
    from experiments.lab.run_state import read_state, restore_state

    import motionlang as ml
    from motionlang.errors import MotionlangError
    sys.path.insert(0, str(ROOT / "experiments"))
    from twostream_parts import RECIPE
    torch.set_num_threads(a.threads)
    try:
        saved = read_state(a.state)
        if not (a.run / "last.pt").is_file():
            restore_state(a.state, a.run)
        weights = dict(RECIPE["lambdas"])
        for spec in a.weight:
            term, _, value = spec.partition("=")
            try:
                weights[term] = float(value)
            except ValueError:
                raise MotionlangError(f"--weight {spec!r}: expected TERM=NUMBER") from None
        run_json = json.loads((a.state / "run.json").read_text(encoding="utf-8"))
        recipe = {**RECIPE, "lambdas": weights,
                  "mirror": bool(run_json["data_options"].get("mirror"))}
        model = ml.train("twostream", saved["data"], a.run, resume=True, epochs=a.epochs,
                         decay_epochs=a.decay_epochs, **recipe)
    except MotionlangError as exc:
        print(f"twostream_resume_state.py: {exc}", file=sys.stderr)
        return 2
    print(model)
    return 0


if __name__ == "__main__":
    sys.exit(main())

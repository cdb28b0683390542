"""Does a normaliser per source give the mixed two-stream model its Bandai figures back? The
package's recipe (procedural corpus + Bandai takes, half of every epoch each, mirrored),
each source's motions z-normalised with the mean and spread of that source's own training
motions (``train twostream --normalise by-source``: ``datasets.position_items.
normalise_by_source``); the model keeps the Bandai normaliser (the last source), so its
motions come out in the Bandai takes' statistics. Every epoch is scored on the Bandai
validation pairs (``--select-evaluator``).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_by_source.py RUN \
        --corpus runs/twostream_parts/corpus --evaluator runs/evaluator_bandai [--epochs 3]

Why: the mix's one normaliser has the spread of the procedural bodies (many sizes), several
times the Bandai takes' in the joints' heights, so the Bandai motions fill a small part of
the model's range; trained on the Bandai takes alone, the model meets the evaluator's bars
(``docs/results/twostream.md``). Fitting one normaliser on the Bandai takes alone was the wrong test (the procedural heights
then span tens of units and dominate the loss: ``twostream_normaliser.py``).
"""
from __future__ import annotations

import sys

from twostream_mix_run import run_probe


def main(argv: list[str] | None = None) -> int:
    return run_probe(__doc__, "twostream_by_source.py", argv, normalise="by-source")


if __name__ == "__main__":
    sys.exit(main())

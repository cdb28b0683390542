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

import sys

from twostream_mix_run import run_probe


def main(argv: list[str] | None = None) -> int:
    def patch(items) -> None:
        fitted = items.dataset_features

        def bandai_fit(records, *args, fit_records=None, **kw):
            own = [r for r in fit_records or [] if getattr(r, "split", None)]
            return fitted(records, *args, fit_records=own or fit_records, **kw)

        items.dataset_features = bandai_fit

    return run_probe(__doc__, "twostream_normaliser.py", argv, patch)


if __name__ == "__main__":
    sys.exit(main())

"""The command line the two-stream mix probes share: the package's recipe (procedural corpus +
Bandai takes, half of every epoch each, mirrored; ``twostream_parts.RECIPE``) trained into
RUN with every epoch scored on the Bandai validation pairs (``--select-evaluator``), resumed
where RUN has a ``last.pt``. A probe changes how the data is prepared by wrapping
``datasets.position_items.build_twostream_data`` (or one of its helpers) and passes extra
``train twostream`` options. Not a probe itself.
"""
from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]


def run_probe(doc: str, name: str, argv: list[str] | None = None,
              patch: Callable[[Any], None] | None = None, **options: Any) -> int:
    """Parse RUN, --corpus, --bandai, --evaluator, --epochs, --threads; call ``patch(the
    twostream_items module)`` first; train; 0, or 2 with one line on a refused input."""
    ap = argparse.ArgumentParser(prog=name, description=doc.split("\n\n")[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--corpus", required=True, help="the procedural corpus (6,000, seed 0)")
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--evaluator", required=True)
    ap.add_argument("--epochs", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    import torch

    import motionlang as ml
    import motionlang.datasets.position_items as items
    from motionlang.errors import MotionlangError
    sys.path.insert(0, str(ROOT / "experiments"))
    from twostream_parts import RECIPE
    torch.set_num_threads(a.threads)
    if patch is not None:
        patch(items)
    bandai = f"bandai:{a.bandai}"
    try:
        model = ml.train("twostream", [f"{a.corpus}@1", f"{bandai}@1"], a.run,
                         resume=(a.run / "last.pt").is_file(), epochs=a.epochs, mirror=True,
                         select_evaluator=a.evaluator, select_data=bandai,
                         **RECIPE, **options)
    except MotionlangError as exc:
        print(f"{name}: {exc}", file=sys.stderr)
        return 2
    print(model)
    return 0

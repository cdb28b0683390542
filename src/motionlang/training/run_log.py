"""The options of every training invocation and the licence note, kept beside the run's
checkpoints (torch-free: the command line reads it at start-up)."""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path


def lead_process() -> bool:
    """True outside torchrun and on its rank 0: the one process that writes run files."""
    return os.environ.get("RANK", "0") == "0"


def log_command(path: Path, args: argparse.Namespace | dict) -> None:
    """Append this invocation's options to ``path`` (one JSON line per invocation, resumes
    included): data options (offsets, --balance, --max-frames, ...) are not in the
    checkpoint, and a resumed run may differ from its start. Under torchrun only rank 0
    writes."""
    from motionlang.utils.atomic import atomic_write
    if not lead_process():
        return
    items = args.items() if isinstance(args, dict) else vars(args).items()
    opts = {k: v for k, v in items if not callable(v)}
    old = path.read_text() if path.exists() else ""
    with atomic_write(path) as fh:
        fh.write(old + json.dumps(opts, sort_keys=True, default=str) + "\n")


#: the licence note of a run trained on Bandai Namco data
LICENSE_FILE = "LICENSE.txt"


def write_license(run: Path, what: str) -> None:
    """:data:`LICENSE_FILE` in ``run``: ``what`` (e.g. "M2L", "judge") was trained on the
    Bandai Namco data (CC BY-NC 4.0), so it and the figures made with it are non-commercial."""
    from motionlang.datasets.bandai import LICENSE
    from motionlang.utils.atomic import atomic_write
    run.mkdir(parents=True, exist_ok=True)
    with atomic_write(run / LICENSE_FILE) as fh:
        fh.write(f"Trained on the Bandai Namco Research Motion Datasets (CC BY-NC 4.0): the "
                 f"{what} and the figures made with it are for non-commercial use only.\n\n"
                 f"Data: {LICENSE}\nLicence text: https://creativecommons.org/licenses/by-nc/4.0/\n")

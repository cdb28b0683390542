"""The options of every training invocation, kept beside the run's checkpoints."""
from __future__ import annotations

import argparse
import json
from pathlib import Path


def log_command(path: Path, args: argparse.Namespace) -> None:
    """Append this invocation's options to ``path`` (one JSON line per invocation, resumes
    included): data options (offsets, --balance, --max-frames, ...) are not in the
    checkpoint, and a resumed run may differ from its start. Under torchrun only rank 0
    writes."""
    import os

    from motionlang.utils.atomic import atomic_write
    if os.environ.get("RANK", "0") != "0":
        return
    opts = {k: v for k, v in vars(args).items() if not callable(v)}
    old = path.read_text() if path.exists() else ""
    with atomic_write(path) as fh:
        fh.write(old + json.dumps(opts, sort_keys=True, default=str) + "\n")

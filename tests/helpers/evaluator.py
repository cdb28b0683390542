"""A tiny procedural corpus and a tiny text-motion evaluator trained on it, through the
command line, for the tests of the Guo protocol and of choosing an epoch by it."""
from __future__ import annotations

from pathlib import Path

#: the evaluator's sizes: trains in seconds
TINY = ["--embed-dim", "8", "--text-hidden", "8", "--motion-hidden", "8",
        "--movement-hidden", "8", "--movement-latent", "8"]


def tiny_corpus(folder: Path) -> Path:
    """48 procedural motions in ``folder/c`` (38 train, 5 validation, 5 test)."""
    from motionlang.cli.main import main
    out = folder / "c"
    assert main(["data", "synth", "--out", str(out), "--n", "48", "--workers", "1"]) == 0
    return out


def tiny_evaluator(corpus: Path, out: Path) -> Path:
    """An evaluator run folder trained one epoch on ``corpus`` (set ``MOTIONLANG_CACHE``
    first)."""
    from motionlang.cli.main import main
    assert main(["train", "evaluator", "--data", str(corpus), "--out", str(out),
                 "--epochs", "1", "--batch-size", "16", *TINY]) == 0
    return out

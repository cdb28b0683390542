"""``motionlang train MODEL ...``: one ``train`` parser that model modules plug into.

A module that trains a model adds one line to ``TRAIN_MODULES`` and defines
``register_train(train_subparsers)``, which adds its ``train X`` parser (with ``func=``).
Modules not written yet are skipped, as in ``cli/main.py``.
"""
from __future__ import annotations

import argparse
import importlib

from motionlang.cli.options import nonneg_float

TRAIN_MODULES = [
    "motionlang.cli.crbm_commands",       # train crbm
    "motionlang.cli.seq2seq_commands",    # train seq2seq (when it exists)
    "motionlang.cli.twostream_commands",  # train twostream (when it exists)
]


def add_schedule_args(p: argparse.ArgumentParser) -> None:
    """``--decay-epochs`` / ``--decay-to`` of the shared trainer (``TrainConfig``)."""
    p.add_argument("--decay-epochs", type=nonneg_float, default=0.0, metavar="N",
                   help="lower the learning rate along a half cosine over the last N epochs "
                        "(also when resuming a run trained at a constant rate; default 0: "
                        "constant)")
    p.add_argument("--decay-to", type=nonneg_float, default=0.01, metavar="F",
                   help="the rate at the last step, as a fraction of --lr (default 0.01)")


def schedule_options(args: argparse.Namespace) -> dict:
    """The ``TrainConfig`` fields set by :func:`add_schedule_args`, checked (call it before
    the data preparation, so that a bad value fails at once)."""
    from motionlang.training.trainer import check_schedule
    check_schedule(args.decay_epochs, args.decay_to, args.epochs)
    return {"decay_epochs": args.decay_epochs, "decay_to": args.decay_to}


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("train", help="train a model",
                                   description="Train a model; see 'motionlang train MODEL -h'.")
    train_sub = parser.add_subparsers(dest="model", metavar="MODEL")
    parser.set_defaults(func=lambda args: (parser.print_help(), 1)[1])
    for name in TRAIN_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                continue
            raise
        hook = getattr(module, "register_train", None)
        if hook is not None:
            hook(train_sub)

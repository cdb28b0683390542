"""``motionlang train MODEL ...``: one ``train`` parser that model modules plug into.

A module that trains a model adds one line to ``TRAIN_MODULES`` and defines
``register_train(train_subparsers)``, which adds its ``train X`` parser (with ``func=``).
Modules not written yet are skipped, as in ``cli/main.py``.
"""
from __future__ import annotations

import argparse
import importlib

TRAIN_MODULES = [
    "motionlang.cli.crbm_commands",       # train crbm
    "motionlang.cli.seq2seq_commands",    # train seq2seq (when it exists)
    "motionlang.cli.twostream_commands",  # train twostream (when it exists)
]


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

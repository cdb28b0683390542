"""``motionlang train MODEL ...``: one ``train`` parser that model modules plug into.

A module that trains a model adds one line to ``TRAIN_MODULES`` and defines
``register_train(train_subparsers)``, which adds its ``train X`` parser (with ``func=``).
Modules not written yet are skipped, as in ``cli/main.py``.

Every ``train X`` takes ``--out DIR``, a run folder (made if missing) holding the final
model under :data:`MODEL_FILES` ``[X]`` plus ``commands.jsonl`` (every invocation's
options); the gradient-trained models also keep ``last.pt`` / ``best.pt`` (resumable
checkpoints), ``history.json``, ``loss_curve.png`` and ``splits/`` there. Every command that
reads a model takes the model file or its run folder.
"""
from __future__ import annotations

import argparse
import importlib

from motionlang.cli.options import (
    nonneg_float,
    nonneg_int,
    output_dir,
    positive_float,
    positive_int,
    seed_int,
)

TRAIN_MODULES = [
    "motionlang.cli.crbm_commands",       # train crbm
    "motionlang.cli.seq2seq_commands",    # train m2l | l2m
    "motionlang.cli.twostream_commands",  # train twostream
    "motionlang.cli.evaluator_commands",  # train evaluator
    "motionlang.cli.judge_commands",      # train judge
]
#: the final model's file name inside a run folder, per ``train`` command
MODEL_FILES = {"m2l": "model.pt", "l2m": "model.pt", "twostream": "model.pt",
               "crbm": "model.npz", "evaluator": "model.pt", "judge": "model.pt"}


def add_out_arg(p: argparse.ArgumentParser, model: str, extra: str = "") -> None:
    """``--out DIR``, the run folder of ``train MODEL`` (default ``runs/MODEL``)."""
    p.add_argument("--out", default=f"runs/{model}", metavar="DIR", type=output_dir,
                   help=f"run folder, made if missing: the model ({MODEL_FILES[model]}), "
                        f"{extra}commands.jsonl (every invocation's options); other commands "
                        "take the folder for its model")


def add_trainer_args(p: argparse.ArgumentParser, **defaults) -> None:
    """The options of the shared trainer (:class:`~motionlang.training.config.TrainConfig`),
    its defaults unless a model's recipe overrides them (``defaults``); ``--resume``."""
    from motionlang.training.config import TrainConfig  # torch-free
    d = {**{f: getattr(TrainConfig, f) for f in
            ("epochs", "batch_size", "lr", "grad_clip", "seed", "checkpoint_every",
             "decay_epochs", "decay_to")}, **defaults}
    p.add_argument("--epochs", type=positive_int, default=d["epochs"],
                   help="passes over the training set")
    p.add_argument("--batch-size", type=positive_int, default=d["batch_size"],
                   help="sequences per optimiser step (all processes together under torchrun)")
    p.add_argument("--lr", type=positive_float, default=d["lr"], help="learning rate")
    p.add_argument("--decay-epochs", type=nonneg_float, default=d["decay_epochs"], metavar="N",
                   help="lower the learning rate along a half cosine over the last N epochs "
                        "(also when resuming a run trained at a constant rate; 0: constant)")
    p.add_argument("--decay-to", type=nonneg_float, default=d["decay_to"], metavar="F",
                   help="the rate at the last step, as a fraction of --lr")
    p.add_argument("--grad-clip", type=nonneg_float, default=d["grad_clip"], metavar="NORM",
                   help="clip the gradient's global L2 norm to NORM (default: "
                        + (f"{d['grad_clip']:g})" if d["grad_clip"] else "no clipping)"))
    p.add_argument("--seed", type=seed_int, default=d["seed"],
                   help="seed of the split, the initial weights and the batch order")
    p.add_argument("--checkpoint-every", type=nonneg_int, default=d["checkpoint_every"],
                   metavar="STEPS", help="also write last.pt every STEPS optimiser steps "
                                         "(0: at the end of each epoch only)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run in --out from its last.pt")


def train_config(args: argparse.Namespace, out_dir, **fields):
    """The :class:`TrainConfig` of :func:`add_trainer_args`' options, checked by the config
    itself (build it before the data preparation, so that a bad value fails at once)."""
    from motionlang.training.config import TrainConfig
    return TrainConfig(epochs=args.epochs, batch_size=args.batch_size, lr=args.lr,
                       grad_clip=args.grad_clip, seed=args.seed, out_dir=str(out_dir),
                       checkpoint_every=args.checkpoint_every, decay_epochs=args.decay_epochs,
                       decay_to=args.decay_to, **fields)


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

"""``motionlang train KIND ...``: one parser per trainable model family.

A family with a recipe (``Family.recipe``, ``recipes``) gets its ``train KIND``
parser generated here from its configs: the recipe's data options, the trainer's
(``TrainConfig``, with the recipe's defaults; not for a recipe with its own training loop,
``Recipe.trainer``) and the model's (its config dataclass, with the recipe's defaults), each
documented field an option (``cli.config_options``). A new family needs nothing in this
folder.

Every ``train X`` takes ``--out DIR``, a run folder (made if missing) holding the final
model (``Family.model_file``) plus ``commands.jsonl`` (every invocation's options); the
gradient-trained models also keep ``last.pt`` / ``best.pt`` (resumable checkpoints),
``history.json``, ``loss_curve.png`` and ``splits/`` there. Every command that reads a model
takes the model file or its run folder.
"""
from __future__ import annotations

import argparse

from motionlang.cli.config_options import (
    add_config_options,
    config_from_args,
    option_fields,  # torch-free
    option_message,
)
from motionlang.cli.options import output_dir
from motionlang.datasets.sources import KINDS, data_help, parse_source
from motionlang.errors import MotionlangError
from motionlang.models.registry import families, family
from motionlang.recipes import recipe_of, run_recipe
from motionlang.training.config import TrainConfig

#: what a run of the shared trainer keeps beside the model (``--out``'s help)
TRAINER_FILES = "best.pt and last.pt (checkpoints), history.json, loss_curve.png, splits/"


def data_source(text: str, kind: str | None = None):
    """argparse type of ``--data``: ``[PREFIX:]DIR[@WEIGHT]`` (``datasets.sources``), of
    ``kind`` where given."""
    try:
        return parse_source(text, kind=kind)
    except MotionlangError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_data_arg(p: argparse.ArgumentParser, several: bool = True,
                 kind: str | None = None) -> None:
    """``--data``: one source, or several (repeatable, ``@W`` weights); with ``kind``, one
    source of that kind (``datasets.sources.KINDS``)."""
    if kind is not None:
        def parse(text: str):
            return data_source(text, kind)
        parse.__name__ = "data source"
        p.add_argument("--data", required=True, type=parse, metavar=f"{KINDS[kind].prefix}DIR",
                       help=KINDS[kind].description)
        return
    p.add_argument("--data", required=True, action="append" if several else "store",
                   type=data_source, metavar="DIR[@W]" if several else "DIR",
                   help=data_help(weights=several) + (
                       " Repeat it to train on several datasets at once (one vocabulary and "
                       "one feature set, each dataset's own split); weight every dataset or "
                       "none (none: every pair once)." if several else ""))


def _register_recipe(train_sub, kind: str) -> None:
    fam, recipe = family(kind), recipe_of(kind)
    p = train_sub.add_parser(kind, help=f"train the {fam.summary}",
                             description=" ".join(filter(None, (f"Train the {fam.summary}.",
                                                                recipe.description))))
    if recipe.data_help:   # one folder in the recipe's own format
        p.add_argument("--data", required=True, metavar="DIR", help=recipe.data_help)
    else:
        add_data_arg(p, recipe.several_sources, recipe.source_kind)
    files = TRAINER_FILES if recipe.run_files is None else recipe.run_files
    p.add_argument("--out", default=f"runs/{kind}", metavar="DIR", type=output_dir,
                   help=f"run folder, made if missing: the model ({fam.model_file}), "
                        f"{files + ', ' if files else ''}commands.jsonl (every invocation's "
                        "options); other commands take the folder for its model")
    add_config_options(p, recipe.data_config)
    if recipe.trainer:   # the shared trainer's options, with the recipe's defaults
        add_config_options(p, TrainConfig, defaults=recipe.train_defaults)
        p.add_argument("--resume", action="store_true",
                       help="continue the run in --out from its last.pt (with the run's "
                            "data, seed and data options)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the run already in --out (its model, checkpoints, history "
                        "and splits are removed first; default: a non-empty --out is refused)")
    model_cls = fam.config_class()
    if model_cls is not None:
        add_config_options(p, model_cls, defaults=recipe.model_defaults)
    p.set_defaults(func=cmd_train, model_kind=kind)


def cmd_train(args: argparse.Namespace) -> int:
    """``train KIND`` of a family with a recipe: the three configs from the options, then
    the recipe."""
    from pathlib import Path

    kind = args.model_kind
    recipe, model_cls = recipe_of(kind), family(kind).config_class()
    train_cfg = config_from_args(TrainConfig, args, out_dir=str(args.out)) \
        if recipe.trainer else None
    data_cfg = config_from_args(recipe.data_config, args)
    model_cfg = {} if model_cls is None else {
        f.name: getattr(args, f.name) for f in option_fields(model_cls)}
    sources = args.data if isinstance(args.data, list) else [args.data]
    try:
        run_recipe(kind, sources, Path(args.out), model_cfg, train_cfg, data_cfg,
                   resume=recipe.trainer and args.resume, overwrite=args.overwrite,
                   options=vars(args))
    except MotionlangError as exc:   # a config's field names -> the options
        message = str(exc)
        for cls in filter(None, (model_cls, TrainConfig if recipe.trainer else None,
                                 recipe.data_config)):
            message = option_message(cls, message)
        raise MotionlangError(message) from None
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("train", help="train a model",
                                   description="Train a model; see 'motionlang train MODEL -h'.")
    train_sub = parser.add_subparsers(dest="model", metavar="MODEL")
    parser.set_defaults(func=lambda args: (parser.print_help(), 1)[1])
    for kind, fam in families().items():
        if fam.recipe is not None:
            _register_recipe(train_sub, kind)

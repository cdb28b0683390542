"""``motionlang models [NAME|FILE]``: the packaged models (name, state, one line each), or one
model's card (a packaged name) or description (a checkpoint file or run folder)."""
from __future__ import annotations

import argparse


def cmd_models(args: argparse.Namespace) -> int:
    from motionlang.models import registry
    if args.model is None:
        print(registry.describe_packaged())
        print("\n'motionlang models NAME' shows a model's card (data, licence, recipe, "
              "figures); any command's --model also takes a checkpoint file or run folder.")
        return 0
    if args.model in registry.PACKAGED:
        print(registry.PACKAGED[args.model].card.rstrip())
        return 0
    path = registry.resolve(args.model)
    print(f"{path}: a model of kind {registry.checkpoint_kind(path)}")
    return 0


def register(subparsers) -> None:
    h = "list the packaged models, or show one's model card"
    p = subparsers.add_parser("models", help=h, description=h)
    p.add_argument("model", nargs="?", default=None, metavar="NAME|FILE",
                   help="a packaged model's name (its card), or a checkpoint file or run "
                        "folder (its kind); none: list the packaged models")
    p.set_defaults(func=cmd_models)

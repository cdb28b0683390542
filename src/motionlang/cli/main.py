"""Entry point of the ``motionlang`` command.

Each subcommand lives in its own module exposing ``register(subparsers)``, which adds a
parser whose ``func`` attribute takes the parsed arguments and returns an exit code.
Errors of motionlang's own types become one line on stderr and exit code 2.

Added here to every command, so that no module repeats them: ``--threads N`` (see
:mod:`motionlang.cli.threads`), help that shows each option's default
(:class:`DefaultsHelpFormatter`), and, under ``torchrun``, one output stream: only rank 0
prints to stdout and logs below warnings.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from pathlib import Path

from motionlang import __version__
from motionlang.cli.options import threads_int
from motionlang.cli.threads import MAX_DEFAULT, default_threads, limit_threads
from motionlang.errors import MotionlangError
from motionlang.training.run_guard import checkpoints, stopped_before_checkpoint
from motionlang.training.run_log import lead_output
from motionlang.utils.atomic import error_line
from motionlang.utils.signals import received, sigterm_unwinds, stopped

# Modules that register subcommands; one line each, order = order in --help.
COMMAND_MODULES = [
    "motionlang.cli.motion_commands",     # check, info, render, convert
    "motionlang.cli.rig_commands",        # rig show | template
    "motionlang.cli.data_commands",       # data ...
    "motionlang.cli.demo",                # demo (the main job)
    "motionlang.cli.train",               # train KIND, one per family with a recipe
    "motionlang.cli.crbm_commands",       # crbm generate | fill | reproduce
    "motionlang.cli.describe_generate",   # describe, generate
    "motionlang.cli.library_commands",    # index, search
    "motionlang.cli.model_commands",      # models [NAME|FILE]
    "motionlang.cli.evaluate",            # evaluate (M2L, round trip)
    "motionlang.cli.evaluate_t2m",        # evaluate-t2m (APE, or Guo with evaluate_guo)
    "motionlang.cli.evaluate_judge",      # evaluate-judge
    "motionlang.cli.serve",               # serve (the web app)
]


class DefaultsHelpFormatter(argparse.HelpFormatter):
    """Appends "(default: X)" to an option's help unless the help already states its
    default; not for flags, required options, or options whose default is None."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if shows_default(action) and "default" not in text.lower():
            text = f"{text} (default: %(default)s)".lstrip()
        return text


def shows_default(action: argparse.Action) -> bool:
    """Whether an option's help must state its default: it has one worth stating."""
    return not (action.required or action.default is None or action.default is False
                or action.default == argparse.SUPPRESS
                or isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction,
                                       argparse._HelpAction, argparse._VersionAction,
                                       argparse._SubParsersAction)))


class OneLineParser(argparse.ArgumentParser):
    """A bad option is one line (``motionlang render: error: argument --fps: ...``) and exit
    code 2, as every other bad input; ``-h`` shows the usage and every option's default.
    Subparsers inherit the class (and so its formatter)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", DefaultsHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def leaf_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """The parsers that run a command: those without subcommands of their own."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return [parser]
    return [leaf for a in subs for p in dict.fromkeys(a.choices.values())
            for leaf in leaf_parsers(p)]


def add_common_options(parser: argparse.ArgumentParser) -> None:
    """``--threads`` on every command (one definition, applied by :func:`main`)."""
    parser.add_argument(
        "--threads", type=threads_int, default=None, metavar="N",
        help="threads for torch and numpy's BLAS (default: OMP_NUM_THREADS if set; else 1 "
             "when the CPU is already busy, its load average near the CPU count; else "
             f"min(CPUs, {MAX_DEFAULT}))")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="motionlang",
        description="Human whole-body motion and natural language.")
    parser.add_argument("--version", action="version", version=f"motionlang {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:   # a listed module that does not import is an error
        importlib.import_module(name).register(sub)
    for leaf in leaf_parsers(parser):
        if leaf is not parser:
            add_common_options(leaf)
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
    threads = getattr(args, "threads", None) or default_threads()
    try:
        with sigterm_unwinds(), limit_threads(threads), lead_output(), \
                warnings.catch_warnings():
            # a warning is one line naming the command, not a source file and line
            warnings.formatwarning = lambda message, *_, **__: (
                f"motionlang {args.command}: warning: {message}\n")
            code = int(args.func(args) or 0)
            distributed = sys.modules.get("motionlang.training.distributed")
            if distributed is not None:  # only the trainer joins a process group (torchrun)
                distributed.finish_distributed()
        return code
    except BrokenPipeError:  # output piped into `head` and the like: not an error
        sys.stderr.close()
        return 0
    except (MotionlangError, OSError) as exc:   # OSError: outside the checked writes
        print(f"motionlang {args.command}: error: {error_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:   # Ctrl-C, or SIGTERM under sigterm_unwinds
        return stopped(exc, _what_now(args))
    except Exception as exc:
        if received() is None:
            raise
        # the interrupt, turned into another error by a library's C code
        return stopped(exc, _what_now(args))


def _what_now(args) -> str:
    """For a stopped ``train``: how its run goes on (or starts again)."""
    out = getattr(args, "out", None) if getattr(args, "command", None) == "train" else None
    if not out or not Path(out).is_dir():
        return ""
    if stopped_before_checkpoint(Path(out)):
        return f"{out} holds no checkpoint yet (--overwrite starts the run again)"
    if checkpoints(Path(out)):
        return f"the same command with --resume continues the run in {out}"
    return ""


if __name__ == "__main__":
    sys.exit(main())

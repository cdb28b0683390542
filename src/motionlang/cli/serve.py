"""``motionlang serve``: the local web app (``motionlang.web``), thin over its options."""
from __future__ import annotations

from motionlang.cli.config_options import add_config_options, config_from_args
from motionlang.web.options import SUMMARY, ServeOptions  # torch- and web-library-free


def cmd_serve(args) -> int:
    from motionlang.web.app import serve
    serve(config_from_args(ServeOptions, args),
          ready=lambda url: print(f"motionlang serve: open {url} (Ctrl-C stops)", flush=True))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("serve", help=SUMMARY, description=SUMMARY[0].upper() + SUMMARY[1:])
    add_config_options(p, ServeOptions)
    p.set_defaults(func=cmd_serve)

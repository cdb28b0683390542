"""Command-line options generated from config dataclasses, and configs built back from them.

A field becomes an option when its ``metadata`` has ``"help"``; other metadata keys:
``"flag"`` (the option's name when it is not ``--field-name``), ``"metavar"``,
``"choices"``, ``"append"`` (repeatable: the field gets the list of texts given),
``"aliases"`` (further names of the option, e.g. an older one that scripts use). The type
comes from the annotation (int, float, bool, or one of them or None; anything else is
passed on as text, for the config to read); a bool field defaulting to False is a flag, one
defaulting to True gets ``--no-NAME``. Argparse only parses the text: every range and
consistency check lives in the config's ``__post_init__``, and :func:`config_from_args`
turns its error into one line naming the option.
"""
from __future__ import annotations

import argparse
import dataclasses
import types
import typing
from typing import Any

from motionlang.cli.options import float_range, parse_number
from motionlang.errors import MotionlangError


def _base_type(hint: Any) -> Any:
    """``X | None`` -> ``X``; any other hint as it is (``list[int]`` stays a list)."""
    if typing.get_origin(hint) not in (typing.Union, types.UnionType):
        return hint
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    return args[0] if len(args) == 1 else hint


def _parse_int(text: str) -> int:
    return parse_number(text, int)


_parse_int.__name__ = "integer"


def flag_of(f: dataclasses.Field) -> str:
    """The option of a config field: ``metadata["flag"]`` or ``--field-name``."""
    return f.metadata.get("flag") or "--" + f.name.replace("_", "-")


def option_fields(cls: type) -> list[dataclasses.Field]:
    """The fields of ``cls`` that are command-line options (those with a help text)."""
    return [f for f in dataclasses.fields(cls) if "help" in f.metadata]


def add_config_options(parser: argparse.ArgumentParser, cls: type, *,
                       defaults: dict[str, Any] | None = None,
                       skip: tuple[str, ...] = (), unset: bool = False) -> None:
    """One option per documented field of the dataclass ``cls`` (see the module
    docstring); ``defaults`` override the dataclass's own (a recipe's), ``skip`` leaves
    fields out. Each option's ``dest`` is the field name. ``unset``: an option not given
    is None (:func:`given_options` leaves it out, so that the field's default, or a value
    set elsewhere such as a ``--model NAME:key=value`` spec, applies) and its help ends
    with the field's default."""
    hints = typing.get_type_hints(cls)
    defaults = defaults or {}
    for f in option_fields(cls):
        if f.name in skip:
            continue
        meta = f.metadata
        default = defaults.get(f.name, f.default)
        if default is dataclasses.MISSING:
            default = None
        base = _base_type(hints[f.name])
        if unset:
            shown = "none" if default is None else str(default).lower() \
                if isinstance(default, bool) else str(default)
            help_ = meta["help"] if "(default" in meta["help"] else \
                f"{meta['help']} (default: {shown})"
            if base is bool:
                flag = "--no-" + flag_of(f)[2:] if default else flag_of(f)
                parser.add_argument(flag, *meta.get("aliases", ()), dest=f.name,
                                    action="store_const", const=not default, default=None,
                                    help=help_)
                continue
            parser.add_argument(flag_of(f), *meta.get("aliases", ()), dest=f.name,
                                type={int: _parse_int, float: float_range()}.get(base, str),
                                default=None, choices=meta.get("choices"),
                                metavar=meta.get("metavar"), help=help_)
            continue
        if base is bool:
            if default:
                parser.add_argument("--no-" + flag_of(f)[2:], dest=f.name,
                                    action="store_false", help=meta["help"])
            else:
                parser.add_argument(flag_of(f), *meta.get("aliases", ()), dest=f.name,
                                    action="store_true", help=meta["help"])
            parser.set_defaults(**{f.name: bool(default)})
            continue
        kind = {int: _parse_int, float: float_range()}.get(base, str)   # any finite number
        parser.add_argument(flag_of(f), *meta.get("aliases", ()), dest=f.name, type=kind,
                            default=default,
                            action="append" if meta.get("append") else "store",
                            choices=meta.get("choices"), metavar=meta.get("metavar"),
                            help=meta["help"])


def config_from_args(cls: type, args: argparse.Namespace, **fixed: Any) -> Any:
    """``cls`` built from the options :func:`add_config_options` added (those present in
    ``args``) and ``fixed`` values; its ``__post_init__`` checks them, and an error names
    the option (``--lr must be a finite number > 0, got 0.0``)."""
    values = {f.name: getattr(args, f.name) for f in option_fields(cls) if hasattr(args, f.name)}
    try:
        return cls(**{**values, **fixed})
    except MotionlangError as exc:
        raise MotionlangError(option_message(cls, str(exc))) from None


def option_message(cls: type, message: str) -> str:
    """A config's error message with its ``Cls.field`` names turned into the options."""
    for f in sorted(option_fields(cls), key=lambda f: -len(f.name)):
        message = message.replace(f"{cls.__name__}.{f.name}", flag_of(f))
    return message


def given_options(cls: type, args: argparse.Namespace) -> dict[str, Any]:
    """The options of ``cls`` (added with ``unset=True``) that were given, by field name."""
    return {f.name: getattr(args, f.name) for f in option_fields(cls)
            if getattr(args, f.name, None) is not None}


def config_values(cfg: Any) -> dict[str, Any]:
    """The option fields of a config instance, for a recipe or ``commands.jsonl``."""
    return {f.name: getattr(cfg, f.name) for f in option_fields(type(cfg))}

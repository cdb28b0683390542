"""``--model [LABEL=]NAME[:key=value,...]``: a text-to-motion model named with its options.

One value names the model (a packaged name, a checkpoint file or a run folder), its sampling
options after ``:`` (the fields of its family's ``Options`` dataclass, ``models.options``) and,
optionally, the label of its row before ``=``::

    --model l2m                                   # row "l2m", default options
    --model l2m:method=sample,width=5,rerank=m2l  # row "l2m:method=sample,width=5,rerank=m2l"
    --model "best of 5=runs/l2m:method=sample,width=5"

Every command that takes text-to-motion models parses, loads and wraps them here
(:func:`load_t2m`), so no command has an option of one family. The help lists each family's
options (``models.options.options_help``) when it is shown: those classes live beside torch
code, which building the parser must not import.
"""
from __future__ import annotations

import argparse
import dataclasses
from typing import Any

from motionlang.api import text_to_motion
from motionlang.errors import MotionlangError
from motionlang.models.options import (
    options_help,
    parse_t2m,  # torch-free
)

SYNTAX = "MODEL[:key=value,...]"


def load_t2m(text: str, flag: str = "--model") -> tuple[str, Any]:
    """(row label, the model behind ``models.t2m.TextToMotion`` with its options) of one
    ``--model`` value: parsed, loaded as any text-to-motion kind and wrapped; a ``method``
    left to the model is "mean", as evaluation rows decode; an option that names another
    model (an L2M's ``rerank``) is loaded now, so that a bad one fails before any data is
    read.

    Raises:
        MotionlangError: one line naming ``flag`` and the value: an unknown option or a bad
            value (the known options listed), or a model that is missing or of another kind.
    """
    label, spec = parse_t2m(text)
    try:
        t2m = text_to_motion(spec.name, spec.options or None)
        if getattr(t2m.options, "method", "") is None:
            # "the model's own way" is the means in an evaluation row: said outright, so
            # that the options' own checks refuse what mean decoding would ignore
            t2m.configure({**dataclasses.asdict(t2m.options), "method": "mean"})
        getattr(t2m, "reranker", None)   # a reranker named in the options loads now
    except MotionlangError as exc:
        raise MotionlangError(f"{flag} {text}: {exc}") from None
    return label, t2m


def load_t2m_models(values: list[str] | None, flag: str = "--model") -> dict[str, Any]:
    """``{row label: model}`` of repeated ``--model`` values (:func:`load_t2m`), in order.

    Raises:
        MotionlangError: as :func:`load_t2m`, or two values with one label.
    """
    out: dict[str, Any] = {}
    for text in values or []:
        label, t2m = load_t2m(text, flag)
        if label in out:
            raise MotionlangError(f"{flag} {text}: a second row named {label!r}; give one "
                                  f"a label ({flag} LABEL=MODEL)")
        out[label] = t2m
    return out


class _OptionsHelp:
    """An action whose help ends with ``models.options.options_help``, made when the help
    is shown."""

    @property
    def help(self) -> str | None:
        if not self._base_help:
            return self._base_help
        return (f"{self._base_help}. Options by kind (a method left unset decodes the "
                f"means): {options_help()}")

    @help.setter
    def help(self, text: str | None) -> None:
        self._base_help = text


class _StoreModel(_OptionsHelp, argparse._StoreAction):
    pass


class _AppendModel(_OptionsHelp, argparse._AppendAction):
    pass


def add_model_arg(parser, *flags: str, help: str, repeat: bool = True, **kw) -> None:
    """Add a text-to-motion model option (``--model`` by default; repeatable, each value
    with an optional row label, unless ``repeat`` is False) whose help ends with every
    family's options."""
    parser.add_argument(*(flags or ("--model",)), action=_AppendModel if repeat else _StoreModel,
                        metavar=("[LABEL=]" if repeat else "") + SYNTAX, help=help, **kw)

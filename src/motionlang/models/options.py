"""A model named with its options: ``NAME[:key=value,...]``, and options dataclasses built
from such text.

Each text-to-motion family states how it samples in a small dataclass (its ``Options``);
a command line names a model and those options in one value, ``--model
l2m:method=sample,width=5``, so no command needs a family-specific option. Values are
converted by the field's annotation (int, float, bool, str, or None for ``none``); range
checks belong to the dataclass's ``__post_init__``.
"""
from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.models.family import load_object
from motionlang.models.registry import families

_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


@dataclass(frozen=True)
class ModelSpec:
    """A model (a packaged name, a checkpoint or a run folder) and its options as text."""

    name: str
    options: dict[str, str] = field(default_factory=dict)

    def __str__(self) -> str:
        if not self.options:
            return self.name
        return self.name + ":" + ",".join(f"{k}={v}" for k, v in self.options.items())


def parse_model_spec(text: str) -> ModelSpec:
    """``"NAME"`` or ``"NAME:key=value,key=value"``; a ``:`` whose tail has no ``=`` is
    part of the name (a path such as ``runs/a:b``).

    Raises:
        MotionlangError: an empty name, an option without ``=`` or a key given twice.
    """
    head, sep, tail = str(text).rpartition(":")
    if not sep or "=" not in tail:
        head, tail = str(text), ""
    if not head:
        raise MotionlangError(f"{text!r}: no model name before the options")
    options: dict[str, str] = {}
    for item in filter(None, (t.strip() for t in tail.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip().replace("-", "_")
        if not eq or not key:
            raise MotionlangError(f"{text}: option {item!r} is not key=value")
        if key in options:
            raise MotionlangError(f"{text}: option {key!r} given twice")
        options[key] = value.strip()
    return ModelSpec(head, options)


def split_label(text: str) -> tuple[str, str]:
    """``[LABEL=]PATH`` -> (label, path). An existing file is a path even if it holds "=";
    otherwise the label ends at the *last* "=", so labels may contain "=" ("h=128")."""
    if Path(text).is_file():
        return Path(text).stem, text
    label, sep, path = text.rpartition("=")
    return (label, path) if sep and label else (Path(text).stem, text.lstrip("="))


def parse_t2m(text: str) -> tuple[str, ModelSpec]:
    """``[LABEL=]NAME[:key=value,...]`` -> (row label, ``ModelSpec``). Without a label the
    row is the model's file stem, followed by its options as given (two rows of one model
    with other options get two names).

    Raises:
        MotionlangError: a malformed option list (:func:`parse_model_spec`).
    """
    if Path(text).exists():   # an existing file or folder is a name, whatever it holds
        return Path(text).stem, ModelSpec(text)
    spec = parse_model_spec(text)
    label, name = split_label(spec.name)
    if name == spec.name:   # no label given: the stem and the options
        label = str(ModelSpec(label, spec.options))
    return label, ModelSpec(name, spec.options)


def _convert(value: Any, hint: Any, where: str) -> Any:
    if not isinstance(value, str):
        return value
    args = typing.get_args(hint)
    if type(None) in args and value.lower() in ("none", "null", ""):
        return None
    base = next((a for a in args if a is not type(None)), hint) if args else hint
    try:
        if base is bool:
            if value.lower() in _TRUE:
                return True
            if value.lower() in _FALSE:
                return False
            raise ValueError
        if base is int:
            return int(value)
        if base is float:
            return float(value)
    except ValueError:
        raise MotionlangError(f"{where}: {value!r} is not a valid "
                              f"{getattr(base, '__name__', base)}") from None
    return value


def build_options(cls: type, values: dict[str, Any] | None, where: str) -> Any:
    """An instance of the options dataclass ``cls`` from ``values`` (text or values),
    checked by its ``__post_init__``; ``where`` names the model in errors.

    Raises:
        MotionlangError: an unknown key (the known ones listed), a value of the wrong type,
            or one the dataclass refuses.
    """
    values = dict(values or {})
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(values) - set(names))
    if unknown:
        known = ", ".join(names) or "none"
        raise MotionlangError(f"{where}: unknown option {', '.join(unknown)} "
                              f"(this model's options: {known})")
    hints = typing.get_type_hints(cls)
    converted = {k: _convert(v, hints[k], f"{where}: {k}") for k, v in values.items()}
    try:
        return cls(**converted)
    except (TypeError, ValueError) as exc:
        raise MotionlangError(f"{where}: {exc}") from None


def field_text(f: dataclasses.Field) -> str:
    """An options field as help shows it: ``width (default 1)``, ``method (sample|beam|mean,
    default none)``."""
    default = f.default if f.default is not dataclasses.MISSING else (
        f.default_factory() if f.default_factory is not dataclasses.MISSING else None)
    shown = "none" if default is None else str(default).lower() if isinstance(
        default, bool) else str(default)
    choices = f.metadata.get("choices")
    return f"{f.name} ({'|'.join(choices) + ', ' if choices else ''}default {shown})"


def options_help() -> str:
    """Each text-to-motion kind and its options with their defaults (and choices), from its
    ``Options`` dataclass: ``l2m: method (sample|beam|mean, default none), width (default
    1), ...; twostream: none``. Imports the families' adapters (torch)."""
    parts = []
    for kind, fam in families().items():
        if fam.text_to_motion is None:
            continue
        owner = fam.model_class() if fam.text_to_motion == "self" else \
            load_object(fam.text_to_motion)
        cls = getattr(owner, "Options", None)
        fields = dataclasses.fields(cls) if cls is not None else ()
        parts.append(f"{kind}: {', '.join(field_text(f) for f in fields) or 'none'}")
    return "; ".join(parts)

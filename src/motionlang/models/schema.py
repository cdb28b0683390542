"""What a model file must hold before anything is built from it: the checkpoint schema.

A checkpoint is data from outside (a download, a colleague's run, a crafted file), so each
of its fields is checked against what its kind needs *before* a model is allocated from
it: the config is a dict whose fields have the types the config dataclass declares and
whose values pass its range checks; every extra entry (vocabulary, normaliser, features,
length model, stage) has the shape its unpacker reads; the weights are checked against the
config by the torch families (:mod:`motionlang.models.checkpoint`) and the CRBM family
(:func:`check_array`). The first bad field is named: ``PATH: a damaged KIND checkpoint
(config.n_features: ...)``.

A schema is written with plain values: a type or tuple of types (``float`` accepts an
int), ``None`` inside a tuple for an entry that may be null, a dict of sub-schemas (keys
required), :class:`ListOf`, :class:`OneOf`, or a function ``value -> problem or None``.
Torch-free, so that the numpy-only CRBM family shares it.
"""
from __future__ import annotations

import dataclasses
import functools
import math
import types
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.models.versions import DAMAGE, damaged


@dataclasses.dataclass(frozen=True)
class ListOf:
    """A list (or tuple) whose items each match ``item``."""
    item: Any


@dataclasses.dataclass(frozen=True)
class OneOf:
    """One of the given constant values."""
    values: tuple


def _is(value: Any, tp: type) -> bool:
    if tp is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if tp is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if tp in (list, tuple):
        return isinstance(value, (list, tuple))
    return isinstance(value, tp)


def _name(tp: Any) -> str:
    return "null" if tp is None else getattr(tp, "__name__", str(tp))


def problem(value: Any, schema: Any, where: str) -> str | None:
    """Why ``value`` does not match ``schema`` (``"WHERE: ..."`` naming the first bad
    field), or None."""
    if callable(schema) and not isinstance(schema, type):
        why = schema(value)
        return f"{where}: {why}" if why else None
    if isinstance(schema, tuple):
        if value is None and None in schema:
            return None
        options = [s for s in schema if s is not None]
        if all(isinstance(s, type) for s in options):
            if any(_is(value, s) for s in options):
                return None
            return (f"{where}: expected {' or '.join(_name(s) for s in schema)}, got "
                    f"{type(value).__name__}")
        return problem(value, options[0], where) if len(options) == 1 else None
    if isinstance(schema, type):
        return None if _is(value, schema) else \
            f"{where}: expected {_name(schema)}, got {type(value).__name__}"
    if isinstance(schema, OneOf):
        return None if value in schema.values else \
            f"{where}: expected one of {list(schema.values)}, got {str(value)[:40]!r}"
    if isinstance(schema, ListOf):
        if not isinstance(value, (list, tuple)):
            return f"{where}: expected a list, got {type(value).__name__}"
        for i, item in enumerate(value):
            bad = problem(item, schema.item, f"{where}[{i}]")
            if bad:
                return bad
        return None
    if isinstance(schema, dict):
        if not isinstance(value, dict):
            return f"{where}: expected a dict, got {type(value).__name__}"
        for key, sub in schema.items():
            if key not in value:
                return f"{where}.{key}: missing"
            bad = problem(value[key], sub, f"{where}.{key}")
            if bad:
                return bad
        return None
    raise TypeError(f"not a schema: {schema!r}")


def finite(value: Any) -> str | None:
    """A schema function: a finite real number."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and \
        math.isfinite(value)
    return None if ok else f"expected a finite number, got {str(value)[:40]!r}"


NUMBERS = ListOf(finite)

# -- the extra entries the families share (see ``models.checkpoint``'s pack_* functions) --
#: ``pack_vocab``: a Vocabulary's ``to_dict`` or a plain token list
VOCAB = (None, {"type": OneOf(("Vocabulary", "list")), "data": (dict, list)})
#: ``pack_normalizer``: a Normalizer's ``to_dict`` or a ``{"mean", "std"}`` dict
NORMALIZER = (None, {"type": OneOf(("Normalizer", "dict")),
                     "data": {"mean": NUMBERS, "std": NUMBERS}})
#: ``pack_features``: a FeatureSet's ``to_dict``
FEATURES = (None, {"kind": str, "config": dict})
#: ``SentenceLength.to_dict``
LENGTH_MODEL = (None, {"words": ListOf(str), "weights": NUMBERS, "bias": finite,
                       "low": int, "high": int})


@functools.cache
def _field_types(config_cls: type) -> dict[str, Any]:
    """Each config field's declared type as a schema (unknown forms: anything goes)."""
    hints = typing.get_type_hints(config_cls)
    return {f.name: _as_schema(hints.get(f.name)) for f in dataclasses.fields(config_cls)}


def _as_schema(tp: Any) -> Any:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if tp in (int, float, bool, str):
        return tp
    if origin in (typing.Union, types.UnionType):
        parts = [_as_schema(a) for a in args if a is not type(None)]
        if len(parts) == 1:
            return (None, parts[0]) if type(None) in args else parts[0]
        return lambda v: None   # a union of several shapes: the config's own check decides
    if origin in (list, tuple):
        item = args[0] if args else Any
        return ListOf(_as_schema(item) if item is not Any else (lambda v: None))
    if origin is dict:
        return dict
    return lambda v: None


def check_config(path: str | Path, kind: str, config_cls: type, config: Any) -> Any:
    """The config dataclass of a checkpoint's ``config``, each field checked first.

    A config that sets fields ``config_cls`` lacks *and* lacks fields it has is no newer
    release's file but another kind's, labelled ``kind``: refused as damaged. (Fields it
    lacks alone: an older file, read with the defaults; fields it adds alone: a newer one,
    refused by :func:`~motionlang.models.versions.check_config_fields`.)

    Raises:
        MotionlangError: ``PATH: a damaged KIND checkpoint (config...: ...)``.
    """
    def bad(why: str) -> MotionlangError:
        return MotionlangError(f"{path}: a damaged {kind} checkpoint ({why})")

    if not isinstance(config, dict):
        raise bad(f"config: expected a dict, got {type(config).__name__}")
    types_ = _field_types(config_cls)
    unknown = sorted(set(config) - set(types_))
    missing = [name for name in types_ if name not in config]
    if unknown and missing:
        raise bad(f"config: fields of another model ({', '.join(unknown[:4])}) and none of "
                  f"{', '.join(missing[:4])}: not a {kind} model's config")
    required = [f.name for f in dataclasses.fields(config_cls)
                if f.default is dataclasses.MISSING and
                f.default_factory is dataclasses.MISSING]
    for name in required:
        if name not in config:
            raise bad(f"config.{name}: missing")
    for name, value in config.items():
        if name in types_:
            why = problem(value, types_[name], f"config.{name}")
            if why:
                raise bad(why)
    if unknown:
        return None   # left to check_config_fields: a newer release's file
    try:
        return config_cls(**config)
    except MotionlangError as exc:
        raise bad(f"config: {exc}") from None
    except (TypeError, ValueError, MemoryError, OverflowError) as exc:
        raise bad(f"config: {type(exc).__name__}: {exc}") from None


def check_entries(path: str | Path, kind: str, d: dict, schemas: dict[str, Any]) -> None:
    """Each extra entry of a checkpoint dict ``d`` that has a schema; an absent entry is
    an older file's (read as it meant), not damage.

    Raises:
        MotionlangError: ``PATH: a damaged KIND checkpoint (ENTRY...: ...)``.
    """
    for key, schema in schemas.items():
        if key in d:
            why = problem(d[key], schema, key)
            if why:
                raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({why})")


def check_array(path: str | Path, kind: str, name: str, shape: tuple[int, ...],
                expected: tuple[int, ...]) -> None:
    """A stored array's shape against the one its config needs."""
    if tuple(shape) != tuple(expected):
        raise MotionlangError(f"{path}: a damaged {kind} checkpoint ({name}: shape "
                              f"{tuple(shape)}, the config needs {tuple(expected)})")


def wrap(path: str | Path, kind: str, build: Callable[[], Any]) -> Any:
    """``build()``, any failure of a file that passed the schema still one line."""
    try:
        return build()
    except (*DAMAGE, MotionlangError, AssertionError, MemoryError) as exc:
        raise MotionlangError(f"{path}: {damaged(kind, exc)}") from exc

"""What the rest of motionlang needs to know about a model family, in one entry.

A family is a folder under ``models/`` (its model, config, recipe and tests) with a
``family.py`` that defines ``FAMILIES``: one :class:`Family` per checkpoint kind it writes.
:mod:`motionlang.models.registry` lists those modules (one line per family) and every other
place (loading, ``train``, text-to-motion, encoders, run folders) reads the entries, so a new
family touches nothing in ``cli/``, ``api.py`` or ``evaluation/``.

Entries name their code as ``"module:attribute"`` strings, imported on first use: reading
the table costs no torch import, and a family's optional dependencies are loaded only when
it is used.
"""
from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from motionlang.errors import MotionlangError


def load_object(spec: str) -> Any:
    """``"package.module:attribute"`` -> the attribute (the module imported on first use).

    Raises:
        MotionlangError: a malformed spec, a module that does not import or a missing
            attribute: a broken family is an error naming the spec, never skipped.
    """
    module, sep, attr = spec.partition(":")
    if not sep or not module or not attr:
        raise MotionlangError(f"{spec!r}: expected 'package.module:attribute'")
    try:
        return getattr(importlib.import_module(module), attr)
    except ImportError as exc:
        raise MotionlangError(f"{spec}: {module} does not import ({exc})") from exc
    except AttributeError:
        raise MotionlangError(f"{spec}: {module} has no {attr}") from None


class ModelClass(Protocol):
    """What a family's ``model`` names: a class whose ``load(path, **kw)`` reads the family's
    checkpoints (the keywords, if any, are the family's own)."""

    load: Callable[..., Any]


@dataclass(frozen=True)
class Family:
    """One model kind and what it can do.

    Attributes:
        kind: the ``kind`` its checkpoints declare (and the name of ``train KIND``).
        model: ``"module:Class"`` whose ``load(path, **kw)`` reads its checkpoints.
        summary: one line for ``--help`` and ``motionlang models``.
        config: ``"module:Class"`` of its config dataclass (torch-free module), whose fields
            carry ``metadata`` for generated command-line options (``cli.config_options``).
        recipe: ``"module:NAME"`` of its ``recipes.Recipe`` (data -> model ->
            trainer -> model file, behind ``train KIND`` and ``ml.train``); None: not
            trainable.
        text_to_motion: ``"module:Class"`` wrapping a loaded model in the text-to-motion
            interface (``models.t2m.TextToMotion``), or ``"self"`` when the model follows
            the small ``models.t2m.SamplingModel`` protocol (the generic adapter does the
            rest); None: not a text-to-motion family.
        describes: ``"module:function"`` turning motion into text, ``(model, motion, *,
            width, length_penalty, rank) -> [(sentence, score), ...]`` best first
            (``describe``); None where the family does not describe motion.
        encodes_text / encodes_motion: ``"module:function"`` ``(model, x) -> (D,) vector``
            for ``ml.encode``; None where the family does not encode that side.
        model_file: the final model's file name inside a training run folder.
    """

    kind: str
    model: str
    summary: str
    config: str | None = None
    recipe: str | None = None
    text_to_motion: str | None = None
    describes: str | None = None
    encodes_text: str | None = None
    encodes_motion: str | None = None
    model_file: str = "model.pt"

    def model_class(self) -> ModelClass:
        return load_object(self.model)

    def config_class(self) -> type | None:
        return None if self.config is None else load_object(self.config)

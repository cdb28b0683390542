"""Self-describing model checkpoints, written and read by one base class.

A checkpoint is a plain dict that ``torch.load(..., weights_only=True)`` accepts (no
pickled classes): ``{"kind", "format", "config", <the family's extra state>, "state_dict"}``.
``format`` is :data:`~motionlang.models.versions.FORMAT_VERSION` (files without one are
format 0, read as before; a newer format is refused by name, since its fields may mean
something else). The extra state is what a family needs besides its weights to run: its
vocabulary, normaliser, the fitted feature set it reads (its ``to_dict``: kind, frame rate,
layout, normaliser), a length model, a training stage. The trainer wraps the dict as
``{"model": <that dict>, "optimizer": ...}``; :func:`read_model_dict` accepts both, so
``best.pt`` of a training run loads directly.

:class:`Checkpointed` holds ``save`` / ``load`` for every torch family; a family sets
``kind`` and ``config_cls`` and fills in the hooks for its extra state.
"""
from __future__ import annotations

import contextlib
import functools
import inspect
from dataclasses import asdict
from pathlib import Path
from typing import Any, ClassVar, cast

import numpy as np
import torch

from motionlang.datasets.text import Vocabulary
from motionlang.errors import MotionlangError
from motionlang.features.base import features_from_dict
from motionlang.features.normalizer import Normalizer
from motionlang.models.schema import check_config, check_entries, wrap
from motionlang.models.versions import (
    DAMAGE,
    FORMAT_VERSION,
    NOT_A_CHECKPOINT,
    check_archive,
    check_config_fields,
    check_format,
    damaged,
    unreadable,
)
from motionlang.utils import limits
from motionlang.utils.atomic import atomic_path


def _plain(x: Any) -> Any:
    """numpy arrays/scalars -> lists/floats so that weights-only loading accepts them."""
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return x


def pack_vocab(vocab: Any) -> dict | None:
    """A Vocabulary (has ``to_dict``) or a plain token list -> a storable dict."""
    if vocab is None:
        return None
    if hasattr(vocab, "to_dict"):
        return {"type": "Vocabulary", "data": _plain(vocab.to_dict())}
    return {"type": "list", "data": [str(t) for t in vocab]}


def unpack_vocab(d: dict | None) -> Any:
    if d is None:
        return None
    if d["type"] == "Vocabulary":
        return Vocabulary.from_dict(d["data"])
    return list(d["data"])


def pack_normalizer(norm: Any) -> dict | None:
    """A Normalizer (``to_dict`` or ``mean``/``std`` attributes) or a dict -> storable dict."""
    if norm is None:
        return None
    if isinstance(norm, dict):
        return {"type": "dict", "data": _plain(norm)}
    if hasattr(norm, "to_dict"):
        return {"type": "Normalizer", "data": _plain(norm.to_dict())}
    return {"type": "dict", "data": _plain({"mean": norm.mean, "std": norm.std})}


def unpack_normalizer(d: dict | None) -> Any:
    if d is None:
        return None
    if d["type"] == "Normalizer":
        return Normalizer.from_dict(d["data"])
    return d["data"]


def pack_features(features: Any) -> dict | None:
    """A fitted ``motionlang.features`` FeatureSet (``to_dict``) -> its JSON-ready dict."""
    return None if features is None else _plain(features.to_dict())


def unpack_features(d: dict | None) -> Any:
    if d is None:
        return None
    return features_from_dict(d)


def write_checkpoint(payload: dict, path: str | Path) -> None:
    """torch.save through an atomic rename (a crash never leaves a torn file).

    Saved through a file object: torch names the archive's root folder after the file it
    is given, and the temporary file's name holds the host and process id; a file object
    gives every checkpoint the same root (``archive/``), so one model saved twice is the
    same bytes, wherever and by whom."""
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        torch.save(payload, fh)


def load_checkpoint(path: str | Path) -> Any:
    """``torch.load(path, weights_only=True)``, its failures as one line.

    A file that is not a checkpoint, a truncated one or one holding pickled classes fails
    the same way; a zip member whose CRC does not match is a damaged file
    (:func:`~motionlang.models.versions.check_archive`). torch's own message advises retrying with ``weights_only=False``, which
    would run code from the file: it is not repeated, and that is never done here.
    """
    path = Path(path)
    if not path.is_file():
        raise MotionlangError(f"{path}: {unreadable(FileNotFoundError())}")
    try:
        with open(path, "rb") as fh:
            fh.read(1)
    except OSError as exc:
        raise MotionlangError(f"{path}: {unreadable(exc)}") from exc
    check_archive(path)
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:   # UnpicklingError, RuntimeError, EOFError, OSError (its zip) ...
        raise MotionlangError(f"{path}: {NOT_A_CHECKPOINT}") from exc


def model_dict(path: str | Path) -> dict:
    """The model dict of a checkpoint (a model file or a trainer checkpoint holding one),
    its format checked; its ``kind`` is not."""
    d = load_checkpoint(path)
    if isinstance(d, dict) and "model" in d and isinstance(d["model"], dict):
        d = d["model"]
    if not isinstance(d, dict) or "kind" not in d:
        raise MotionlangError(f"{path}: not a motionlang model checkpoint")
    check_format(path, d.get("format", 0))
    return d


def read_model_dict(path: str | Path, kind: str) -> dict:
    """Load a model checkpoint (or a trainer checkpoint holding one), check format and kind."""
    d = model_dict(path)
    if d.get("kind") != kind:
        raise MotionlangError(f"{path}: not a {kind} checkpoint (found {d.get('kind')!r})")
    return d


def _check_options(cls: type[Checkpointed], kw: dict[str, Any]) -> None:
    """A ``load`` option the family's :meth:`Checkpointed.from_state` does not take is the
    caller's mistake: a TypeError now, not a damaged file later."""
    params = inspect.signature(cls.from_state).parameters
    if any(p.kind is p.VAR_KEYWORD for p in params.values()):
        return
    takes = {n for n, p in params.items()
             if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)} - {"config", "state"}
    unknown = sorted(set(kw) - takes)
    if unknown:
        raise TypeError(f"{cls.__name__}.load() got unexpected keyword argument(s) "
                        f"{', '.join(unknown)}")


@contextlib.contextmanager
def _meta_init_skipped():
    """``torch.nn.init``'s in-place initialisers leave ``meta`` tensors as they are while
    the block runs. A shape check needs no values, and drawing random numbers into a meta
    tensor goes through torch's Python reference ops, which import ``torch._dynamo``: seconds
    that every command that loads a model would pay. Real tensors are initialised as ever."""
    init = torch.nn.init
    saved = {name: getattr(init, name) for name in dir(init)
             if name.endswith("_") and not name.startswith("_")
             and callable(getattr(init, name))}

    def skipping(original):
        @functools.wraps(original)
        def initialise(tensor, *args, **kwargs):
            if isinstance(tensor, torch.Tensor) and tensor.is_meta:
                return tensor
            return original(tensor, *args, **kwargs)
        return initialise

    for name, fn in saved.items():
        setattr(init, name, skipping(fn))
    try:
        yield
    finally:
        for name, fn in saved.items():
            setattr(init, name, fn)


def check_weights(path: str | Path, cls: Any, config: Any, d: dict, kw: dict) -> None:
    """The file's ``state_dict`` against the model its config describes, before the model
    is built: the model is made on the ``meta`` device (shapes, no memory), its size held
    to ``max_memory_bytes``, and every stored tensor must be one of its own, of its shape.

    Raises:
        MotionlangError: ``PATH: a damaged KIND checkpoint (state_dict...: ...)``.
    """
    def bad(why: str) -> MotionlangError:
        return MotionlangError(f"{path}: a damaged {cls.kind} checkpoint ({why})")

    stored = d.get("state_dict")
    if not isinstance(stored, dict):
        raise bad("state_dict: missing" if stored is None else
                  f"state_dict: expected a dict of tensors, got {type(stored).__name__}")
    for name, value in stored.items():
        if not isinstance(value, torch.Tensor):
            raise bad(f"state_dict.{name}: expected a tensor, got {type(value).__name__}")
    if config is None:
        return
    with torch.device("meta"), _meta_init_skipped():
        skeleton = wrap(path, cls.kind, lambda: cls.from_state(config, d, **kw))
    wanted = skeleton.state_dict()
    tensors = [*skeleton.parameters(), *skeleton.buffers()]
    need = sum(t.numel() * t.element_size() for t in tensors)
    too_big = limits.message("max_memory_bytes", need, "memory its config asks for")
    if too_big:
        raise bad(f"config: {too_big}")
    for name, value in stored.items():
        if name not in wanted:
            raise bad(f"state_dict.{name}: not a tensor of this {cls.kind} model")
        if tuple(value.shape) != tuple(wanted[name].shape):
            raise bad(f"state_dict.{name}: shape {tuple(value.shape)}, the config needs "
                      f"{tuple(wanted[name].shape)}")
    # a tensor the file lacks is left to load_state_dict: a family's load hook may fill
    # in what files from before it existed lack


class Checkpointed:
    """Mixin of every torch model family: one self-describing checkpoint file.

    A family (an ``nn.Module`` subclass listing this mixin first) sets

    * ``kind`` — written into the file and checked on load;
    * ``config_cls`` — its config dataclass: the file's ``config`` is ``asdict(config)``,
      rebuilt as ``config_cls(**config)``; a field it lacks is refused by name
      (a file from a newer motionlang), never read as damage;

    and overrides the hooks it needs (each has a default that stores nothing):

    * :meth:`checkpoint_state` — extra entries beside config and weights (vocabulary,
      normaliser, ``features``, length model, stage ...), weights-only loadable (plain
      lists, dicts, numbers, strings; tensors);
    * :meth:`from_state` — the model built from its config and those entries, before its
      weights are loaded; ``load``'s keyword arguments arrive here (e.g. a text encoder);
      a file written before an entry existed has none: read it as the older files meant;
    * :meth:`restore_state` — what is set after the weights (a training stage ...).

    Every failure to rebuild a file that opened (a missing entry, a wrong shape, a bad
    value) is one line naming the file: ``PATH: a damaged KIND checkpoint (...)``. Before
    anything is allocated, :meth:`load` checks the config's field types and values, each
    entry of ``state_schema`` and every tensor's name and shape against a model built on
    torch's ``meta`` device (no memory) from that config (:func:`check_weights`).
    """

    kind: ClassVar[str]
    config_cls: ClassVar[type]
    #: the schema of each extra entry (:mod:`motionlang.models.schema`), checked on load
    state_schema: ClassVar[dict[str, Any]] = {}
    config: Any

    # -- hooks --------------------------------------------------------------------------
    def checkpoint_state(self) -> dict[str, Any]:
        """Entries stored beside ``kind``, ``format``, ``config`` and ``state_dict``."""
        return {}

    @classmethod
    def from_state(cls, config: Any, state: dict[str, Any]) -> Any:
        """The model (weights not yet loaded) from its config and the file's entries. A
        family whose ``load`` takes options (a text encoder, word vectors) declares them
        here as keyword parameters."""
        return cast(Any, cls)(config)

    def restore_state(self, state: dict[str, Any]) -> None:
        """Set what the file holds besides the weights, after they are loaded."""

    # -- written once -------------------------------------------------------------------
    def config_dict(self) -> dict[str, Any]:
        return asdict(self.config)

    def to_checkpoint(self) -> dict[str, Any]:
        """The checkpoint dict (what the trainer stores under ``"model"``)."""
        module: Any = self   # an nn.Module: the family lists this mixin before it
        # on the CPU whatever the model trained on: a file from a GPU run reads anywhere
        weights = {k: v.detach().cpu() for k, v in module.state_dict().items()}
        return {"kind": self.kind, "format": FORMAT_VERSION, "config": self.config_dict(),
                **self.checkpoint_state(), "state_dict": weights}

    @classmethod
    def from_checkpoint(cls, d: dict[str, Any], **kw: Any) -> Any:
        """Rebuild from a checkpoint dict (checked by :meth:`load`); in eval mode."""
        model = cls.from_state(cls.config_cls(**d["config"]), d, **kw)
        model.load_state_dict(d["state_dict"])
        model.restore_state(d)
        return model.eval()

    def save(self, path: str | Path) -> None:
        """One self-describing file (atomic write: a crash never leaves a torn file)."""
        write_checkpoint(self.to_checkpoint(), path)

    @classmethod
    def load(cls, path: str | Path, **kw: Any) -> Any:
        """Rebuild from a file written by :meth:`save` or by the trainer; in eval mode.
        ``kw`` go to :meth:`from_state`.

        Raises:
            MotionlangError: no such file, not a checkpoint, another kind, a newer format
                or config field, or a damaged file; always one line naming the file.
        """
        _check_options(cls, kw)
        d = read_model_dict(path, cls.kind)
        config = check_config(path, cls.kind, cls.config_cls, d.get("config"))
        check_config_fields(cls.config_cls, d.get("config"), path, cls.kind)
        check_entries(path, cls.kind, d, cls.state_schema)
        check_weights(path, cls, config, d, kw)
        try:
            return cls.from_checkpoint(d, **kw)
        except (*DAMAGE, MotionlangError) as exc:
            raise MotionlangError(f"{path}: {damaged(cls.kind, exc)}") from exc

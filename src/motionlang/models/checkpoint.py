"""Self-describing model checkpoints: config, vocabulary, normaliser and weights in one file.

A checkpoint is a plain dict that ``torch.load(..., weights_only=True)`` accepts (no
pickled classes): ``{"kind", "format", "config", "vocab", "normalizer", "features",
"state_dict"}``; ``format`` is :data:`FORMAT_VERSION` (files without one are format 0, read
as before; a newer format is refused by name, since its fields may mean something else);
the fitted feature set (whose own normaliser the data went through) rides along as its
``to_dict``. The trainer wraps it as ``{"model": <that dict>, "optimizer": ...}``;
:func:`read_model_dict` accepts both, so ``best.pt`` of a training run loads directly.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.versions import FORMAT_VERSION, check_format
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
        from motionlang.datasets.text import Vocabulary
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
        try:
            from motionlang.features.normalizer import Normalizer
            return Normalizer.from_dict(d["data"])
        except (ImportError, AttributeError):  # features layer without from_dict: keep the dict
            pass
    return d["data"]


def pack_features(features: Any) -> dict | None:
    """A fitted ``motionlang.features`` FeatureSet (``to_dict``) -> its JSON-ready dict."""
    return None if features is None else _plain(features.to_dict())


def unpack_features(d: dict | None) -> Any:
    if d is None:
        return None
    from motionlang.features.base import features_from_dict
    return features_from_dict(d)


def write_checkpoint(payload: dict, path: str | Path) -> None:
    """torch.save through an atomic rename (a crash never leaves a torn file)."""
    with atomic_path(path) as tmp:
        torch.save(payload, tmp)


def load_checkpoint(path: str | Path) -> Any:
    """``torch.load(path, weights_only=True)``, its failures as one line.

    A file that is not a checkpoint, a truncated one or one holding pickled classes fails
    the same way. torch's own message advises retrying with ``weights_only=False``, which
    would run code from the file: it is not repeated, and that is never done here.
    """
    path = Path(path)
    if not path.is_file():
        raise MotionlangError(f"{path}: no such checkpoint file")
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except OSError as exc:
        raise MotionlangError(f"{path}: cannot read checkpoint: "
                              f"{exc.strerror or type(exc).__name__}") from exc
    except Exception as exc:   # UnpicklingError, RuntimeError (zip), EOFError, ...
        raise MotionlangError(f"{path}: not a readable motionlang checkpoint (truncated, "
                              f"or another kind of file)") from exc


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


def check_config_fields(config_cls: type, d: dict, path: str | Path, kind: str) -> None:
    """One clear line when a checkpoint's config sets fields ``config_cls`` (a dataclass) does
    not have: a file written by a newer motionlang, whose options this one cannot honour
    (without this the constructor's TypeError reads as a damaged file)."""
    from dataclasses import fields
    config = d.get("config")
    if not isinstance(config, dict):
        return
    unknown = sorted(set(config) - {f.name for f in fields(config_cls)})
    if unknown:
        raise MotionlangError(f"{path}: this {kind} checkpoint sets {', '.join(unknown)}, which "
                              f"this version of motionlang does not know: it was written by a "
                              f"newer one (upgrade motionlang to read it)")


def read_model_dict(path: str | Path, kind: str) -> dict:
    """Load a model checkpoint (or a trainer checkpoint holding one), check format and kind."""
    d = model_dict(path)
    if d.get("kind") != kind:
        raise MotionlangError(f"{path}: not a {kind} checkpoint (found {d.get('kind')!r})")
    return d


class Seq2SeqCheckpoint:
    """Mixin: self-describing checkpoints for models built as
    ``cls(config_cls(**config), vocab, normalizer, features)`` (M2L and L2M).

    The subclass sets ``kind`` (written into the file and checked on load) and ``config_cls``.
    """

    kind: str
    config_cls: type

    def to_checkpoint(self) -> dict:
        from dataclasses import asdict
        return {"kind": self.kind, "format": FORMAT_VERSION, "config": asdict(self.config),
                "vocab": pack_vocab(self.vocab), "normalizer": pack_normalizer(self.normalizer),
                "features": pack_features(self.features), "state_dict": self.state_dict()}

    @classmethod
    def from_checkpoint(cls, d: dict):
        model = cls(cls.config_cls(**d["config"]), unpack_vocab(d.get("vocab")),
                    unpack_normalizer(d.get("normalizer")), unpack_features(d.get("features")))
        model.load_state_dict(d["state_dict"])
        return model.eval()

    def save(self, path: str | Path) -> None:
        """One self-describing file (atomic write)."""
        write_checkpoint(self.to_checkpoint(), path)

    @classmethod
    def load(cls, path: str | Path):
        """Rebuild from a file written by :meth:`save` or by the trainer; in eval mode."""
        d = read_model_dict(path, cls.kind)
        check_config_fields(cls.config_cls, d, path, cls.kind)
        try:
            return cls.from_checkpoint(d)
        except (KeyError, TypeError, ValueError, RuntimeError) as exc:
            raise MotionlangError(f"{path}: a damaged {cls.kind} checkpoint "
                                  f"({type(exc).__name__}: {str(exc).splitlines()[0]})") from exc

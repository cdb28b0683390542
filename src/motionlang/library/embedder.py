"""A model that puts sentences and motions in one space, with the identity an index keeps.

Which models qualify is read from the family table (``Family.encodes_text`` and
``encodes_motion`` both set), never from a kind's name. An index records the model's name
and a digest of its checkpoint, so that a search with another model, or with the same name
after the file changed, is refused instead of comparing vectors of two spaces.
"""
from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.datasets.download import sha256_file
from motionlang.errors import MotionlangError
from motionlang.kinematics.motion import Motion
from motionlang.models.family import load_object
from motionlang.models.registry import PACKAGED, families, kinds_with, load_model, resolve

#: the packaged model an index uses when none is named, where the installation has it
DEFAULT_MODEL = "retrieval"


def joint_kinds() -> tuple[str, ...]:
    """The model kinds whose family encodes both sentences and motions."""
    motion = set(kinds_with("encodes_motion"))
    return tuple(k for k in kinds_with("encodes_text") if k in motion)


def default_model() -> str:
    """:data:`DEFAULT_MODEL` where it is packaged and present.

    Raises:
        MotionlangError: it is not; the message says which models to name instead.
    """
    p = PACKAGED.get(DEFAULT_MODEL)
    if p is not None and p.path.is_file():
        return DEFAULT_MODEL
    fit = [q.name for q in PACKAGED.values() if q.kind in joint_kinds() and q.path.is_file()]
    raise MotionlangError(f"no packaged {DEFAULT_MODEL} model in this installation: name a "
                          f"model that encodes sentences and motions (of kind "
                          f"{' or '.join(joint_kinds())}" + (f", e.g. {fit[0]}" if fit else "")
                          + ")")


def weights_digest(model: Any) -> str:
    """SHA-256 of a loaded torch model's weights (names, shapes and values, in order).

    Raises:
        MotionlangError: the model is not a torch module (pass its file instead).
    """
    import torch
    if not isinstance(model, torch.nn.Module):
        raise MotionlangError(f"cannot tell a loaded {type(model).__name__} apart from "
                              "another: pass the model's file or name")
    h = hashlib.sha256()
    for name, tensor in model.state_dict().items():
        t = tensor.detach().cpu().contiguous()
        h.update(f"{name}{tuple(t.shape)}{t.dtype}".encode())
        h.update(t.numpy().tobytes() if t.dtype != torch.bfloat16 else t.float().numpy().tobytes())
    return h.hexdigest()


@dataclass
class Embedder:
    """Sentences and motions to vectors of one space, and the identity of what does it.

    Attributes:
        name: what the user called the model (a packaged name or a path), for messages and
            for loading it again at search time.
        digest: SHA-256 of its checkpoint file, or of its weights when it was given loaded.
        encode_text: a sentence -> (D,) vector; encode_motion: a Motion -> (D,) vector.
        model: the loaded model, if any.
        embedded: motions embedded so far (what a run of the index reports).
    """

    name: str
    digest: str
    encode_text: Callable[[str], np.ndarray]
    encode_motion: Callable[[Motion], np.ndarray]
    model: Any = None
    embedded: int = 0

    @classmethod
    def of_model(cls, model: Any, name: str, digest: str) -> Embedder:
        """The embedder of a loaded model, its encoders read from its family's entry.

        Raises:
            MotionlangError: its family does not encode both sentences and motions.
        """
        kind = getattr(model, "kind", None)
        fam = families().get(kind) if isinstance(kind, str) else None
        if fam is None or fam.encodes_text is None or fam.encodes_motion is None:
            raise MotionlangError(f"{name}: a {kind or type(model).__name__} model does not "
                                  f"put sentences and motions in one space (models that do: "
                                  f"{', '.join(joint_kinds()) or 'none'})")
        text, motion = load_object(fam.encodes_text), load_object(fam.encodes_motion)
        return cls(name, digest, partial(text, model), partial(motion, model), model)

    @classmethod
    def load(cls, model: Any = None) -> Embedder:
        """An embedder from a packaged name, a checkpoint file or run folder, a loaded
        model, an Embedder (returned as it is) or None (:func:`default_model`).

        Raises:
            MotionlangError: a missing model, or one that does not encode both sides.
        """
        if isinstance(model, Embedder):
            return model
        if model is None or isinstance(model, (str, Path)):
            name = str(model or default_model())
            loaded = load_model(name, kind=joint_kinds() or None)
            path = resolve(name)
            # a file is kept by its absolute path: a search from another folder finds it
            return cls.of_model(loaded, name if name in PACKAGED else str(path.resolve()),
                                sha256_file(path))
        return cls.of_model(model, f"a loaded {getattr(model, 'kind', 'model')} model",
                            weights_digest(model))

    def motion(self, motion: Motion) -> np.ndarray:
        """(D,) float32 vector of a motion."""
        self.embedded += 1
        return np.asarray(self.encode_motion(motion), dtype=np.float32)

    def text(self, sentence: str) -> np.ndarray:
        """(D,) float32 vector of a sentence."""
        return np.asarray(self.encode_text(sentence), dtype=np.float32)

    @property
    def identity(self) -> dict:
        """``{"name", "digest"}``, as an index stores it."""
        return {"name": self.name, "digest": self.digest}

    def check(self, identity: dict, where: str) -> None:
        """Raise unless ``identity`` (an index's) is this model's."""
        if identity.get("digest") != self.digest:
            raise MotionlangError(f"{where}: made with the model {identity.get('name')!r} "
                                  f"(digest {str(identity.get('digest'))[:12]}), not "
                                  f"{self.name!r} (digest {self.digest[:12]})")

"""Describing by retrieval: the sentences of a bank nearest to a motion in a joint
text-motion space.

A user who has their own captions (or any list of sentences, such as KIT-ML's annotations)
gets descriptions in those words: every bank sentence is embedded once by a model whose family
encodes both sentences and motions into one space (``Family.encodes_text`` and
``encodes_motion``), the motion is embedded by the same model, and the bank sentences of
highest cosine similarity are the description. Which models qualify is read from the registry,
never from a kind's name.

A bank file is one of:

* a text file: one sentence a line (blank lines skipped);
* ``captions.csv`` (header ``file,text``) or ``captions.jsonl`` (``{"file", "text"}``), the
  captions of a custom dataset (``datasets.custom``);
* ``.json``: a list of sentences, or KIT-ML's annotations as TMR ships them
  (``{id: {"annotations": [{"text": ...}, ...]}, ...}``).

Sentences are kept once each (compared by their words, case, punctuation and KIT-ML's
spelling corrections aside: ``datasets.text.normalize``), the first spelling, in the
file's order.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from motionlang.datasets.cache import cached
from motionlang.datasets.custom import read_captions
from motionlang.datasets.text import normalize
from motionlang.errors import DatasetError, MotionlangError
from motionlang.library.embedder import default_model, joint_kinds
from motionlang.models.registry import PACKAGED
from motionlang.utils.progress import progress
from motionlang.utils.sidecar import parse_json

if TYPE_CHECKING:
    from motionlang.library.embedder import Embedder


def _json_sentences(data: Any, path: Path) -> list[str]:
    if isinstance(data, list) and all(isinstance(s, str) for s in data):
        return list(data)
    if isinstance(data, dict):
        out = []
        for key, entry in data.items():
            notes = entry.get("annotations") if isinstance(entry, dict) else None
            if not isinstance(notes, list):
                raise DatasetError(f"{path}: entry {key!r} has no 'annotations' list")
            for i, a in enumerate(notes):
                if isinstance(a, dict) and "text" not in a:
                    raise DatasetError(f"{path}: entry {key!r}, annotation {i} has no 'text'")
                out.append(a["text"] if isinstance(a, dict) else a)
        if all(isinstance(s, str) for s in out):
            return out
    raise DatasetError(f"{path}: expected a list of sentences or KIT-ML annotations "
                       "({id: {\"annotations\": [{\"text\": ...}]}})")


def read_bank(path: str | Path) -> list[str]:
    """The distinct sentences of a bank file (formats in the module docstring).

    Raises:
        DatasetError: a missing or malformed file, or one without a sentence.
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: sentence bank not found")
    ext = path.suffix.lower()
    if ext in (".csv", ".jsonl"):
        sentences = [text for _, _, text in read_captions(path)]
    else:
        try:
            text = path.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as exc:
            raise DatasetError(f"{path}: cannot read ({exc})") from None
        if ext == ".json":
            try:
                sentences = _json_sentences(parse_json(text, str(path)), path)
            except DatasetError:
                raise
            except MotionlangError as exc:   # invalid, too deep: one line naming the file
                raise DatasetError(str(exc)) from None
        else:
            sentences = text.splitlines()
    seen: dict[str, str] = {}
    for s in (" ".join(s.split()) for s in sentences):
        key = normalize(s)
        if key and key not in seen:
            seen[key] = s
    if not seen:
        raise DatasetError(f"{path}: no sentences in the bank")
    return list(seen.values())


def default_bank_model() -> str:
    """The packaged model a bank is embedded with when none is named: the index's default
    (``library.embedder``) where it is installed, else the first packaged model that encodes
    both sentences and motions."""
    try:
        return default_model()
    except MotionlangError:
        found = [p.name for p in PACKAGED.values()
                 if p.kind in joint_kinds() and p.path.is_file()]
        if not found:
            raise
        return found[0]


def _unit(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float32)
    norm = np.linalg.norm(x, axis=-1, keepdims=True)
    return x / np.maximum(norm, 1e-12)


@dataclass
class SentenceBank:
    """Bank sentences and their unit vectors (N, D) in a model's joint space."""

    sentences: list[str]
    vectors: np.ndarray

    def nearest(self, vector: np.ndarray, k: int) -> list[tuple[str, float]]:
        """The ``k`` sentences of highest cosine with ``vector`` (D,), best first (ties in
        bank order)."""
        cos = self.vectors @ _unit(vector)
        top = np.argsort(-cos, kind="stable")[:k]
        return [(self.sentences[i], float(cos[i])) for i in top]


def embed_bank(embedder: Embedder, sentences: list[str], *,
               show_progress: bool | None = None) -> SentenceBank:
    """Embed ``sentences`` with a joint text-motion model (``library.embedder``). The
    vectors are cached (``datasets.cache``) under the model's digest and the sentences', so
    that a bank is embedded once per model, not once per run."""

    def compute() -> dict[str, np.ndarray]:
        bar = progress(sentences, desc="bank", unit="sentences",
                       disable=None if show_progress is None else not show_progress)
        return {"vectors": _unit(np.stack([embedder.text(s) for s in bar]))}

    digest = hashlib.sha256("\n".join(sentences).encode("utf-8")).hexdigest()
    key = {"what": "sentence bank", "version": 1, "model": embedder.digest,
           "sentences": digest}
    return SentenceBank(list(sentences), cached(key, compute, name="bank")["vectors"])

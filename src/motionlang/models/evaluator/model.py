"""The text-motion evaluator of Guo et al. 2022: a text encoder and a motion encoder into
one embedding space, where a caption lies near the motions it describes. The yardstick of
text-to-motion papers (R-precision, FID, MM-Dist, Diversity: ``evaluation.metrics.t2m``) is
computed on its embeddings.

Input: motion feature rows (T, F) in their own units (the HumanML3D vectors of
``features.h3d_vectors``, or any per-frame features), normalised here with the evaluator's
mean/std, cut to a multiple of 4 frames; captions as ``word/POS`` tokens
(``text.caption_tokens``). Architecture and parameter names: ``layers``. Training as the
public ``TextMotionMatchTrainer`` (loss: ``EvaluatorConfig.loss``), with two differences:
the movement encoder is trained with the rest instead of being taken from a separately
trained autoencoder and frozen; a training crop keeps every whole unit of 4 frames (the
public loader sometimes drops one more) at a random offset.

Checkpoint (``save``/``load``, registry kind ``"evaluator"``): ``{"kind", "format",
"config", "normalizer": {"mean", "std"}, "features", "state_dict"}``; ``features`` says
which rows the evaluator reads (``features.h3d_vectors.rows_layout``: layout, body, frame
rate, unit, size; None for rows of another size), read off ``motion_dim`` unless given. :meth:`load_official` reads the
public ``finest.tar`` and its ``mean.npy``/``std.npy``.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from motionlang.errors import MotionlangError
from motionlang.features.h3d_vectors import layout_for_dim
from motionlang.models.checkpoint import Checkpointed, load_checkpoint, unpack_normalizer
from motionlang.models.evaluator.config import EvaluatorConfig
from motionlang.models.evaluator.layers import MotionEncoder, MovementEncoder, TextEncoder
from motionlang.models.evaluator.text import caption_tokens, glove_50d, text_inputs
from motionlang.models.schema import NORMALIZER

#: the public checkpoint's entry of each module
OFFICIAL_KEYS = ("movement_encoder", "motion_encoder", "text_encoder")


def _array(x: Any) -> np.ndarray:
    if isinstance(x, (str, Path)):
        x = np.load(x, allow_pickle=False)
    return np.asarray(x, dtype=np.float32).reshape(-1)


class TextMotionEvaluator(Checkpointed, nn.Module):
    """Text and motion encoders of one embedding space (see module docstring).

    Args:
        config: sizes and loss.
        mean, std: (F,) per-column statistics of the motion features (default 0 and 1).
        vectors: word vectors (``dim``, ``word in v``, ``v[word]``; default GloVe 6B 50d,
            which needs ``config.word_dim == 50``); they are not stored in checkpoints.
        features: the rows' description (``features.h3d_vectors.rows_layout``); default:
            the HumanML3D body whose rows have ``config.motion_dim`` numbers, if any.
    """

    kind = "evaluator"
    config_cls = EvaluatorConfig

    def __init__(self, config: EvaluatorConfig, mean=None, std=None, vectors=None,
                 features: dict | None = None):
        super().__init__()
        c = self.config = config
        #: which rows the evaluator reads: layout, body, frame rate, unit, size (or None)
        self.features = layout_for_dim(c.motion_dim) if features is None else dict(features)
        self.movement_encoder = MovementEncoder(c.input_dim, c.movement_hidden,
                                                c.movement_latent, c.dropout)
        self.motion_encoder = MotionEncoder(c.movement_latent, c.motion_hidden, c.embed_dim)
        self.text_encoder = TextEncoder(c.word_dim, c.n_pos, c.text_hidden, c.embed_dim)
        self.set_normalizer(np.zeros(c.motion_dim) if mean is None else mean,
                            np.ones(c.motion_dim) if std is None else std)
        self._vectors = vectors

    # -- inputs -------------------------------------------------------------------------
    def set_normalizer(self, mean, std) -> None:
        """Per-column mean and std (F,) of the motion features; a zero std counts as 1."""
        mean, std = _array(mean), _array(std)
        if mean.shape != (self.config.motion_dim,) or std.shape != mean.shape:
            raise MotionlangError(f"evaluator mean/std must be ({self.config.motion_dim},), "
                                  f"got {mean.shape} and {std.shape}")
        if not (np.isfinite(mean).all() and np.isfinite(std).all()):
            raise MotionlangError("evaluator mean/std are not finite")
        self.mean, self.std = mean, np.where(std > 0, std, 1.0).astype(np.float32)

    @property
    def vectors(self):
        if self._vectors is None:
            if self.config.word_dim != 50:
                raise MotionlangError(f"an evaluator of {self.config.word_dim}-d words needs "
                                      "its word vectors (vectors=...); GloVe 50d is built in")
            self._vectors = glove_50d()
        return self._vectors

    def _motion_tensor(self, motions: Sequence, random_crop: bool
                       ) -> tuple[torch.Tensor, torch.Tensor]:
        """Rows (T_i, F) -> normalised (B, max L_i, F') and lengths L_i = 4 floor(T_i / 4)
        (a motion of under 4 rows is padded with its last row)."""
        u, out = self.config.unit_length, []
        for m in motions:
            m = np.asarray(m, dtype=np.float32)
            if m.ndim != 2 or m.shape[1] != self.config.motion_dim or not len(m):
                raise MotionlangError(f"evaluator motions must be (T >= 1, "
                                      f"{self.config.motion_dim}), got {m.shape}")
            if len(m) < u:
                m = np.concatenate([m, np.repeat(m[-1:], u - len(m), axis=0)])
            n = len(m) // u * u
            start = int(torch.randint(len(m) - n + 1, ())) if random_crop else 0
            x = (m[start:start + n] - self.mean) / self.std
            out.append(torch.from_numpy(x[:, :self.config.input_dim]))
        lengths = torch.tensor([len(x) for x in out])
        return nn.utils.rnn.pad_sequence(out, batch_first=True), lengths

    def _text_tensor(self, tokens: Sequence[Sequence[str]]
                     ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        pairs = [text_inputs(t, self.vectors, self.config.max_words) for t in tokens]
        words = nn.utils.rnn.pad_sequence([torch.from_numpy(w) for w, _ in pairs], True)
        pos = nn.utils.rnn.pad_sequence([torch.from_numpy(p) for _, p in pairs], True)
        return words, pos, torch.tensor([len(w) for w, _ in pairs])

    def collate(self, items: Sequence[dict]) -> dict[str, torch.Tensor]:
        """Items ``{"motion": (T, F) rows, "caption": str, "tokens": [word/POS] or
        absent}`` -> the batch of :meth:`loss`; in training mode each motion's crop starts
        at a random offset."""
        motion, m_len = self._motion_tensor([it["motion"] for it in items], self.training)
        tokens = [caption_tokens(it.get("caption", ""), it.get("tokens")) for it in items]
        words, pos, w_len = self._text_tensor(tokens)
        # pairs whose captions are the same words: not negatives of each other (templated
        # data such as Bandai's repeats a caption across many motions)
        key = [" ".join(t.rpartition("/")[0] for t in toks) for toks in tokens]
        same = torch.tensor([[a == b for b in key] for a in key])
        return {"motion": motion, "motion_lengths": m_len, "words": words, "pos": pos,
                "word_lengths": w_len, "same_caption": same}

    # -- encoders -----------------------------------------------------------------------
    def encode_motion(self, motion: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """Normalised (B, T, F') with T and lengths multiples of 4 -> (B, D)."""
        codes = self.movement_encoder(motion)
        return self.motion_encoder(codes, torch.div(lengths, self.config.unit_length,
                                                    rounding_mode="floor"))

    def encode_text(self, words, pos, lengths) -> torch.Tensor:
        """(B, L, W), (B, L, 15), (B,) -> (B, D)."""
        return self.text_encoder(words, pos, lengths)

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """``{"loss", ...}`` of a batch (:meth:`collate`): hinge (``"pos"``, ``"neg"``:
        mean squared distance of the matched pairs and mean squared hinge of the pairs
        shifted by a random 1..B-1 in training, of all mismatched pairs in eval mode; pairs
        whose captions are the same words, ``batch["same_caption"]``, are not negatives) or
        InfoNCE (``"nce"``; the same pairs left out of its softmax)."""
        t = self.encode_text(batch["words"], batch["pos"], batch["word_lengths"])
        m = self.encode_motion(batch["motion"], batch["motion_lengths"])
        c = self.config
        if c.loss == "infonce":
            logits = -torch.cdist(t, m) / c.temperature
            target = torch.arange(len(t))
            eye = torch.eye(len(t), dtype=torch.bool)
            same = batch.get("same_caption", eye) & ~eye   # same caption: not a negative
            logits = logits.masked_fill(same, float("-inf"))
            nce = (F.cross_entropy(logits, target) + F.cross_entropy(logits.T, target)) / 2
            return {"loss": nce, "nce": nce.detach()}
        pos = (t - m).pow(2).sum(-1).mean()
        neg = torch.zeros(())
        if len(t) > 1:
            # training: one random shift, as the public code; evaluation: every mismatched
            # pair, so that validation losses do not depend on a draw
            d = (t[:, None] - m[None]).pow(2).sum(-1).clamp_min(1e-12).sqrt()   # (B, B)
            rows = torch.arange(len(t))
            negative = ~batch.get("same_caption", torch.eye(len(t), dtype=torch.bool))
            negative &= ~torch.eye(len(t), dtype=torch.bool)
            if self.training:
                cols = (rows + int(torch.randint(1, len(t), ()))) % len(t)
                d, keep = d[rows, cols], negative[rows, cols]
            else:
                keep = negative
            if keep.any():
                neg = (c.margin - d[keep]).clamp_min(0).pow(2).mean()
        return {"loss": pos + neg, "pos": pos.detach(), "neg": neg.detach()}

    @torch.no_grad()
    def embed_motions(self, motions: Sequence, batch_size: int = 256) -> np.ndarray:
        """Motion rows [(T_i, F)] -> (N, D) float64 embeddings (eval mode, crop from 0)."""
        self.eval()
        out = [self.encode_motion(*self._motion_tensor(motions[i:i + batch_size], False))
               for i in range(0, len(motions), batch_size)]
        return torch.cat(out).double().numpy() if out else np.zeros((0, self.config.embed_dim))

    @torch.no_grad()
    def embed_texts(self, captions: Sequence[str], tokens: Sequence | None = None,
                    batch_size: int = 256) -> np.ndarray:
        """Captions (with their ``word/POS`` tokens if given) -> (N, D) float64."""
        self.eval()
        toks = [caption_tokens(c, None if tokens is None else tokens[i])
                for i, c in enumerate(captions)]
        out = [self.encode_text(*self._text_tensor(toks[i:i + batch_size]))
               for i in range(0, len(toks), batch_size)]
        return torch.cat(out).double().numpy() if out else np.zeros((0, self.config.embed_dim))

    # -- checkpoints --------------------------------------------------------------------
    state_schema = {"normalizer": NORMALIZER, "features": (None, dict)}

    def checkpoint_state(self) -> dict[str, Any]:
        return {"normalizer": {"type": "dict", "data": {"mean": self.mean.tolist(),
                                                        "std": self.std.tolist()}},
                "features": self.features}

    @classmethod
    def from_state(cls, config: EvaluatorConfig, state: dict[str, Any], vectors=None
                   ) -> TextMotionEvaluator:
        norm = unpack_normalizer(state.get("normalizer")) or {}
        return cls(config, norm.get("mean"), norm.get("std"), vectors, state.get("features"))

    @classmethod
    def load_official(cls, source, mean, std, config: EvaluatorConfig | None = None,
                      vectors=None) -> TextMotionEvaluator:
        """The public evaluator: ``source`` its ``finest.tar`` (path, read weights-only) or
        the dict in it (``movement_encoder``, ``motion_encoder``, ``text_encoder`` state
        dicts in the names of the public modules); ``mean``/``std`` its ``mean.npy`` /
        ``std.npy`` (paths or arrays). ``config`` default: read off the weights' shapes
        (:func:`official_config`). 300-d words need ``vectors``."""
        named = isinstance(source, (str, Path))
        d = load_checkpoint(source) if named else source
        missing = [k for k in OFFICIAL_KEYS
                   if not (isinstance(d, dict) and isinstance(d.get(k), dict))]
        if missing:
            raise MotionlangError(f"{source if named else 'dict'}: not the public "
                                  f"evaluator's checkpoint (no {missing[0]})")
        config = config or official_config(d)
        model = cls(config, mean, std, vectors)
        for key in OFFICIAL_KEYS:
            try:
                getattr(model, key).load_state_dict(d[key])
            except RuntimeError as exc:
                raise MotionlangError(f"the public {key} does not fit {config}: "
                                      f"{str(exc).splitlines()[0]}") from exc
        return model.eval()


def official_config(d: dict) -> EvaluatorConfig:
    """The :class:`EvaluatorConfig` of a public checkpoint dict, from its weights' shapes
    (the foot contacts left out: ``drop_last`` 4)."""
    try:
        conv = d["movement_encoder"]["main.0.weight"]        # (hidden, F - 4, 4)
        latent = d["movement_encoder"]["out_net.weight"].shape[0]
        motion = d["motion_encoder"]["input_emb.weight"]     # (H_motion, latent)
        text = d["text_encoder"]
        return EvaluatorConfig(
            motion_dim=conv.shape[1] + 4, drop_last=4, movement_hidden=conv.shape[0],
            movement_latent=latent, motion_hidden=motion.shape[0],
            word_dim=text["pos_emb.weight"].shape[0], n_pos=text["pos_emb.weight"].shape[1],
            text_hidden=text["input_emb.weight"].shape[0],
            embed_dim=text["output_net.3.weight"].shape[0])
    except (KeyError, AttributeError, IndexError) as exc:
        raise MotionlangError(f"not the public evaluator's weights (no {exc})") from None

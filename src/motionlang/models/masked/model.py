"""The masked-token text-to-motion model (MoMask-style, Guo et al. 2024; tokens as T2M-GPT,
Zhang et al. 2023), on motionlang's 21-joint position features.

* :class:`~.tokenizer.Tokenizer`: position rows (T, F) at the features' rate -> tokens
  (T / 4, Q) of a residual quantiser, and back.
* :class:`~.transformer.MaskTransformer` over the base tokens, :class:`~.transformer.
  ResidualTransformer` for codebooks 1..Q-1, :class:`~.transformer.LengthEstimator`; all read
  a frozen sentence vector (MiniLM's last hidden state, mean-pooled; cached per sentence).

Training stages, one model: ``stage = "tokenizer"`` trains the tokenizer (frame, velocity,
global-position and foot-velocity reconstruction, commitment; codebooks by EMA); ``stage =
"generator"`` freezes it and trains the three token models on the training motions' tokens;
``stage = "decoder"`` retrains the tokenizer's decoder alone, encoder and codebooks frozen
(quantiser dropout still applies, so it keeps decoding coarse codes alone). ``loss`` and
``collate`` follow the stage, so the shared trainer runs each.

Sampling (:meth:`MaskedModel.sample`, the ``models.t2m.SamplingModel`` protocol): the
length from the caller or the estimator, base tokens by iterative masked decoding with
classifier-free guidance (:mod:`.sampling`), the finer codebooks by the residual
transformer, decoded to rows and to global positions. :meth:`MaskedModel.inbetween` fixes
the tokens of kept frames and generates only the others (:mod:`.inbetween`).

Checkpoint (``save``/``load``, kind ``"masked"``): ``{"kind", "format", "config",
"features", "stage", "caption_words", "state_dict"}``; the sentence encoder's weights are not in it.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from motionlang.errors import MotionlangError
from motionlang.features.positions import PositionFeatures, facing_yaw, positions_to_rows
from motionlang.models.checkpoint import Checkpointed, pack_features, unpack_features
from motionlang.models.masked import goal as goals
from motionlang.models.masked import sampling
from motionlang.models.masked.config import DOWN, MaskedConfig, MaskedOptions
from motionlang.models.masked.inbetween import arrival_miss, gaps, join, kept_tokens
from motionlang.models.masked.path import global_errors
from motionlang.models.masked.tokenizer import Tokenizer, pad_frames
from motionlang.models.masked.transformer import (
    LengthEstimator,
    MaskTransformer,
    ResidualTransformer,
)
from motionlang.models.schema import ListOf
from motionlang.models.text_tokens import TransformerTokens

#: "decoder" retrains the tokenizer's decoder alone: the tokens, and a generator trained on
#: them, stay valid
STAGES = ("tokenizer", "decoder", "generator")
MOTION_STAGES = ("tokenizer", "decoder")


class MaskedModel(Checkpointed, nn.Module):
    """Tokenizer, token transformers and length estimator (see module docstring).

    Args:
        config: sizes and losses; ``text_dim`` 0 is read off the sentence encoder.
        features: the fitted ``PositionFeatures`` (they travel in the checkpoint); None: not
            fitted (trainable on rows, but ``sample`` cannot return positions).
        text_encoder: a ``models.text_tokens.CachedTokens`` whose token mean is the sentence
            vector; None: the one the config names, built on first use.
    """

    kind = "masked"
    config_cls = MaskedConfig
    Options = MaskedOptions
    deterministic = False

    def __init__(self, config: MaskedConfig, features: PositionFeatures | None = None,
                 text_encoder: Any = None):
        super().__init__()
        if features is not None and not isinstance(features, PositionFeatures):
            raise MotionlangError(f"the masked model reads positions features, not "
                                  f"{getattr(features, 'kind', type(features).__name__)!r}")
        self._text = text_encoder
        self.features = features
        if config.text_dim <= 0:
            config = replace(config, text_dim=int(self.text.dim))
        self.config = config
        self.stage = STAGES[0]
        self.tokenizer = Tokenizer(config)
        self.generator = MaskTransformer(config)
        self.residual = ResidualTransformer(config)
        self.length = LengthEstimator(config)

    # -- text ---------------------------------------------------------------------------
    @property
    def text(self) -> Any:
        """The frozen token-feature source (built from the config on first use)."""
        if self._text is None:
            self._text = TransformerTokens(self.config.text_model, (self.config.text_layer,))
        return self._text

    def sentence_vectors(self, sentences: Sequence[str]) -> torch.Tensor:
        """(B, text_dim) float32: each sentence's token features, averaged (cached by the
        token source)."""
        feats = self.text.many(list(sentences))
        return torch.stack([f.mean(0) for f in feats]).to(self.device)

    @property
    def device(self) -> torch.device:
        return next(self.parameters()).device

    @property
    def fps(self) -> float:
        return float(self.config.fps)

    def set_stage(self, stage: str) -> MaskedModel:
        """Train the tokenizer, its decoder alone, or (frozen tokenizer) the token models."""
        if stage not in STAGES:
            raise MotionlangError(f"stage must be one of {', '.join(STAGES)}, got {stage!r}")
        self.stage = stage
        for p in self.tokenizer.parameters():
            p.requires_grad_(stage == "tokenizer")
        for p in self.tokenizer.decoder.parameters():
            p.requires_grad_(stage in MOTION_STAGES)
        for part in (self.generator, self.residual, self.length):
            for p in part.parameters():
                p.requires_grad_(stage == "generator")
        for p in self.parameters():
            if not p.requires_grad:
                # the trainer zeroes gradients rather than dropping them, and AdamW decays
                # every parameter that has one: a frozen part must have none
                p.grad = None
        return self

    # -- training -----------------------------------------------------------------------
    def collate(self, items: Sequence[dict]) -> dict[str, Any]:
        """Items -> a batch of :meth:`loss`. Tokenizer stage: ``{"motion": (T, F) rows}``,
        cropped to ``config.window`` at a random offset in training. Generator stage:
        ``{"tokens": (L, Q) ints, "sentence": str}``."""
        if not items:
            raise MotionlangError("cannot collate an empty batch")
        if self.stage in MOTION_STAGES:
            return self._collate_motion(items)
        toks = [torch.as_tensor(np.asarray(it["tokens"]), dtype=torch.long) for it in items]
        L = max(len(t) for t in toks)
        tokens = torch.zeros(len(toks), L, toks[0].shape[1], dtype=torch.long)
        valid = torch.zeros(len(toks), L, dtype=torch.bool)
        for i, t in enumerate(toks):
            tokens[i, :len(t)], valid[i, :len(t)] = t, True
        batch = {"tokens": tokens.to(self.device), "valid": valid.to(self.device),
                 "text": self.sentence_vectors([str(it["sentence"]) for it in items])}
        if self.generator.goal is not None:
            goal, gap = goals.batch_goals([it.get("track") for it in items],
                                          [len(t) for t in toks], L, self.config.goal,
                                          self.fps)
            batch.update(goal=goal.to(self.device), gap=gap.to(self.device))
        return batch

    def _collate_motion(self, items: Sequence[dict]) -> dict[str, Any]:
        window = self.config.window_frames
        seqs = []
        for it in items:
            x = torch.as_tensor(np.asarray(it["motion"]), dtype=torch.float32)
            if len(x) > window:
                start = int(torch.randint(0, len(x) - window + 1, ())) if self.training else 0
                x = x[start:start + window]
            seqs.append(x)
        T = max(len(x) for x in seqs)
        T += (-T) % DOWN
        motion = torch.stack([pad_frames(torch.cat(
            [x, x[-1:].expand(T - len(x), -1)]).unsqueeze(0))[0] for x in seqs])
        frames = torch.arange(T)[None] < torch.tensor([len(x) for x in seqs])[:, None]
        return {"motion": motion.to(self.device), "frames": frames.to(self.device)}

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """Named loss terms of a batch of the current stage; ``"loss"`` is minimised."""
        if self.stage in MOTION_STAGES:
            return self._tokenizer_loss(batch)
        return self._generator_loss(batch)

    def _tokenizer_loss(self, batch: dict) -> dict[str, torch.Tensor]:
        x, frames = batch["motion"], batch["frames"]
        tokens = frames.reshape(len(x), -1, DOWN).any(-1)
        out = self.tokenizer(x, tokens, frozen=self.stage == "decoder")
        recon = F.smooth_l1_loss(out["recon"][frames], x[frames])
        both = frames[:, 1:] & frames[:, :-1]
        dx, dr = x[:, 1:] - x[:, :-1], out["recon"][:, 1:] - out["recon"][:, :-1]
        vel = F.smooth_l1_loss(dr[both], dx[both]) if both.any() else recon * 0
        c = self.config
        total = recon + c.velocity * vel + c.commit * out["commit"]
        terms = {"recon": recon.detach(), "velocity": vel.detach(),
                 "commit": out["commit"].detach()}
        if (c.path > 0 or c.foot > 0) and self.features is not None \
                and self.features.normalizer is not None:
            norm = self.features.normalizer
            path, foot = global_errors(norm.inverse(out["recon"]), norm.inverse(x), frames,
                                       c.fps)
            total = total + c.path * path + c.foot * foot
            terms.update(path_m=path.detach(), foot_ms=foot.detach())
        return {"loss": total, **terms}

    def _generator_loss(self, batch: dict) -> dict[str, torch.Tensor]:
        tokens, valid, text = batch["tokens"], batch["valid"], batch["text"]
        c = self.config
        drop = torch.rand(len(tokens), device=tokens.device) < c.cond_drop if self.training \
            else None
        # a motion given a gap is masked inside it only, as in-betweening sees it
        gap = batch.get("gap")
        region = valid if gap is None else torch.where(gap.any(1, keepdim=True), gap, valid)
        masked = sampling.training_mask(region)
        seen = sampling.corrupt(tokens[..., 0], masked, c.codes, self.generator.mask_id)
        logits = self.generator(seen, text, valid, drop, batch.get("goal"))
        base = F.cross_entropy(logits[masked], tokens[..., 0][masked])
        total, out = base, {"base": base.detach()}
        if c.quantizers > 1:
            j = int(torch.randint(1, c.quantizers, ()))
            res_logits = self.residual(tokens, j, text, valid, drop)
            res = F.cross_entropy(res_logits[valid], tokens[..., j][valid])
            total, out["residual"] = total + res, res.detach()
        length = self.length.loss(text, valid.sum(1))
        out.update(loss=total + 0.1 * length, length=length.detach())
        return out

    # -- tokens -------------------------------------------------------------------------
    @torch.no_grad()
    def tokenize(self, rows: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Normalised rows [(T_i, F)] -> tokens [(ceil(T_i / 4), Q) int64], every codebook."""
        self.tokenizer.eval()
        out = []
        for x in rows:
            t = torch.as_tensor(np.asarray(x), dtype=torch.float32, device=self.device)
            out.append(self.tokenizer.encode(t[None])[0].cpu().numpy())
        return out

    @torch.no_grad()
    def reconstruct(self, rows: np.ndarray, n_q: int | None = None) -> np.ndarray:
        """Normalised rows (T, F) -> the same rows through tokens (first ``n_q`` codebooks;
        None: all) and back (T, F)."""
        tokens = torch.as_tensor(self.tokenize([rows])[0], device=self.device)
        k = self.config.quantizers if n_q is None else n_q
        return self.tokenizer.decode(tokens[None, :, :k])[0, :len(rows)].cpu().numpy()

    def frames_for(self, sentence: str) -> int | None:
        """The length (frames at :attr:`fps`) the estimator gives the sentence: its
        likeliest number of tokens, 4 frames each."""
        with torch.no_grad():
            self.length.eval()
            logits = self.length(self.sentence_vectors([sentence]))
        return int(logits.argmax(-1)[0]) * DOWN + DOWN

    def unknown_words(self, sentence: str) -> list[str]:
        """None: a pretrained sentence encoder reads every word."""
        return []

    # -- sampling -----------------------------------------------------------------------
    @torch.no_grad()
    def sample_tokens(self, texts: Sequence[str], n_tokens: Sequence[int], *, seed: int,
                      options: MaskedOptions, known: torch.Tensor | None = None,
                      kept: torch.Tensor | None = None, goal: torch.Tensor | None = None
                      ) -> torch.Tensor:
        """Tokens (B, L, Q) of every codebook for ``texts``, ``n_tokens`` long (positions
        past a motion's length are padding); ``known`` (B, L, Q) / ``kept`` (B, L) fix
        tokens, ``goal`` (B, L, GOAL_DIM) says where each gap arrives (in-betweening)."""
        if self.training:   # eval() walks every submodule: not on each call
            self.eval()
        L = max(n_tokens)
        valid = torch.arange(L, device=self.device)[None] < torch.tensor(
            list(n_tokens), device=self.device)[:, None]
        text = self.sentence_vectors(texts)
        g = torch.Generator().manual_seed(int(seed))
        def rows(x: torch.Tensor, n: int) -> torch.Tensor:   # the batch, once or twice
            return x if n == len(x) else torch.cat([x] * (n // len(x)))

        base = sampling.decode_base(
            lambda tok, drop: self.generator(
                tok, rows(text, len(tok)), rows(valid, len(tok)), drop,
                None if goal is None else rows(goal.to(self.device), len(tok))), valid,
            self.generator.mask_id, steps=options.steps, guidance=options.guidance,
            temperature=options.temperature, top_k=options.top_k, generator=g,
            known=None if known is None else known[..., 0], kept=kept)
        return sampling.decode_residual(
            lambda tok, j, drop: self.residual(tok, j, rows(text, len(tok)),
                                               rows(valid, len(tok)), drop), base,
            self.config.quantizers, guidance=options.res_guidance, known=known, kept=kept)

    def _positions(self, rows: np.ndarray, start: Any = (0.0, 0.0, 0.0)) -> np.ndarray:
        if self.features is None or not self.features.fitted:
            raise MotionlangError("this masked model has no fitted features: it cannot "
                                  "return positions")
        return self.features.decode(rows, start, pin_root=True)

    def sample(self, texts: Sequence[str], lengths: Sequence[int | None], *, seed: int,
               options: MaskedOptions) -> list[np.ndarray]:
        """Global 21-joint positions (T, 21, 3) metres at :attr:`fps` for each sentence,
        ``lengths`` in frames (None: the estimator's), sentence i drawn with ``seed + i``."""
        frames = [int(n) if n is not None else int(self.frames_for(t) or DOWN)
                  for t, n in zip(texts, lengths, strict=True)]
        out = []
        for i, (text, n) in enumerate(zip(texts, frames, strict=True)):
            n_tok = min(self.config.max_tokens, max(1, -(-n // DOWN)))
            tokens = self.sample_tokens([text], [n_tok], seed=seed + i, options=options)
            rows = self.tokenizer.decode(tokens)[0].cpu().numpy()
            rows = np.concatenate([rows, np.repeat(rows[-1:], max(0, n - len(rows)), 0)])
            out.append(self._positions(rows[:n]))
        return out

    def inbetween(self, text: str, p21: np.ndarray, keep: np.ndarray, *, seed: int = 0,
                  options: MaskedOptions | None = None, foot_lock: bool = False
                  ) -> np.ndarray:
        """Global positions (T, 21, 3) at :attr:`fps` and the frames to keep (T,) bool ->
        a motion of T frames that has the kept frames and, elsewhere, frames generated
        for ``text``: of the :meth:`inbetween_drafts`, the one that arrives closest to the
        kept frames, joined to them by ``inbetween.join`` (``foot_lock``: planted feet held,
        before and after the join)."""
        p21 = np.asarray(p21, dtype=np.float64)
        keep = np.asarray(keep, dtype=bool)
        drafts = self.inbetween_drafts(text, p21, keep, seed=seed, options=options)
        best = min(drafts, key=lambda d: arrival_miss(d, p21, keep))
        return join(best, p21, keep, self.fps, foot_lock=foot_lock)

    def inbetween_drafts(self, text: str, p21: np.ndarray, keep: np.ndarray, *,
                         seed: int = 0, options: MaskedOptions | None = None
                         ) -> list[np.ndarray]:
        """``options.drafts`` motions (T, 21, 3), drawn in one batch, that keep the tokens
        of the kept frames (T,) bool of ``p21`` and regenerate the others for ``text``, a
        model with goals told where each gap must arrive (``goal.kept_goal``); decoded by
        :meth:`decode_placed`, not yet joined to the kept frames."""
        options = options or MaskedOptions()
        p21 = np.asarray(p21, dtype=np.float64)
        keep = np.asarray(keep, dtype=bool)
        if p21.ndim != 3 or p21.shape[1:] != (21, 3) or len(keep) != len(p21):
            raise MotionlangError(f"in-betweening needs positions (T, 21, 3) and T kept "
                                  f"flags, got {p21.shape} and {keep.shape}")
        if self.features is None or not self.features.fitted:
            raise MotionlangError("this masked model has no fitted features")
        rows = self.features.encode_positions(p21)
        n_tok = -(-len(rows) // DOWN)
        if n_tok > self.config.max_tokens:
            raise MotionlangError(f"in-betweening: the motion is {len(rows)} frames, this "
                                  f"model generates at most {self.config.max_tokens * DOWN}")
        n = options.drafts
        known = torch.as_tensor(self.tokenize([rows])[0], device=self.device)[None]
        kept_np = kept_tokens(keep)
        kept = torch.as_tensor(kept_np, device=self.device)[None]
        raw = positions_to_rows(p21)[0]
        goal = torch.as_tensor(goals.kept_goal(goals.root_track(raw), kept_np, self.fps))
        tokens = self.sample_tokens([text] * n, [n_tok] * n, seed=seed, options=options,
                                    known=known.expand(n, -1, -1), kept=kept.expand(n, -1),
                                    goal=goal[None].expand(n, -1, -1))
        return [self.decode_placed(g[:len(rows)], p21, keep)
                for g in self.tokenizer.decode(tokens).cpu().numpy()]

    def decode_placed(self, rows: np.ndarray, p21: np.ndarray, keep: np.ndarray
                      ) -> np.ndarray:
        """Normalised rows (T, F) of a draft -> its global positions (T, 21, 3), decoded
        whole (kept tokens too, so the generated frames join their decoded neighbours
        smoothly; ``blend`` then puts the kept frames of ``p21`` back exactly). The path
        integrated from frame 0 gathers the tokenizer's small heading errors, and a gap
        entered a few degrees off arrives a stride off: from each gap's last kept frame on,
        the draft is placed again from ``p21``'s own place and heading there."""
        p21 = np.asarray(p21, dtype=np.float64)
        out = self._positions(rows, positions_to_rows(p21[:1])[1])
        for a, _ in gaps(keep):
            if a > 0:
                place = (p21[a - 1, 0, 0], p21[a - 1, 0, 2], facing_yaw(p21[a - 1:a])[0])
                out[a - 1:] = self._positions(rows[a - 1:], place)
        return out

    # -- checkpoints --------------------------------------------------------------------
    #: the words of the training captions (the recipe sets them; None: a file from before)
    caption_words: list[str] | None = None
    state_schema = {"stage": str, "caption_words": (None, ListOf(str))}

    def checkpoint_state(self) -> dict[str, Any]:
        fitted = self.features is not None and self.features.fitted
        return {"features": pack_features(self.features) if fitted else None,
                "stage": self.stage, "caption_words": self.caption_words}

    @classmethod
    def from_state(cls, config: MaskedConfig, state: dict[str, Any],
                   text_encoder: Any = None) -> MaskedModel:
        # files from before the path and foot terms and goals were trained without them
        written = state.get("config") or {}
        off: dict[str, Any] = {k: 0.0 for k in ("path", "foot", "goal") if k not in written}
        config = replace(config, **off)
        return cls(config, unpack_features(state.get("features")), text_encoder)

    def restore_state(self, state: dict[str, Any]) -> None:
        self.set_stage(str(state.get("stage", STAGES[-1])))
        words = state.get("caption_words")
        self.caption_words = None if words is None else [str(w) for w in words]

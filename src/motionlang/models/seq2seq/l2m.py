"""Language-to-motion seq2seq model (Plappert, Mandery & Asfour 2018, Section 4.2).

Encoder: word embeddings with layer normalisation, then bidirectional GRUs; context = last
output of the last layer (both directions). Decoder: GRUs with layer normalisation (paper:
3 x 400), every layer fed the context, the previous frame and the previous layer's output.
Output: a mixture of K (paper: 20) diagonal Gaussians over the next frame plus a Bernoulli
"active" flag (1 = the motion goes on after this frame; 0 on a motion's last frame).
Loss: the paper's stable surrogate ``-sum_k pi_k log N_k`` (or the exact mixture NLL with
``loss="exact"``) per frame, plus the flag's binary cross-entropy. Optional additive
attention as in :mod:`motionlang.models.seq2seq.m2l`.

Frames are model features (usually normalised); the first decoder input is a zero frame.

Options beyond the paper, all off by default: ``input_noise`` adds Gaussian noise to
the teacher-forced previous frames while training, so that predicting "the previous frame
again" stops being nearly free and the decoder has to use the sentence (without it, a model
trained on our corpus copies its input and generates standing); ``time_input`` feeds the
elapsed time, which makes the end-of-motion flag learnable from a clock instead of from a
count the GRU state has to keep. ``progress_input`` feeds the fraction of the motion done,
t / (T - 1), so that the decoder knows which part of the sentence it is in: T is the true
length while training; generation plans it from the sentence with the checkpoint's
``length_model`` (:class:`motionlang.models.length.SentenceLength`) or takes it from the
caller, and stops there at the latest.

``input_mask`` (per feature, 0 = hidden) keeps features of the previous frames from the
decoder while it still predicts them: with the root's ground velocity and heading change
hidden, the way the body moves cannot be copied from the frame before and has to come from
the sentence and the rest of the pose.

Also ``rollout`` (scheduled sampling, Bengio et al. 2015): while training, each
previous-frame input is, with probability ``rollout``, the frame the model itself sampled
at the step before instead of the true one (no gradient through the sample; with
``rollout_input="mean"`` its expected frame instead of a draw, for a model that generates
deterministically with mean decoding); the
probability ramps up linearly over ``rollout_warmup`` optimiser steps. Teacher forcing alone
teaches "continue the frames you are shown": on our corpus such a model, left to run on its
own frames, settles into standing even when primed with true frames. Training on its
own frames makes it follow the sentence instead. It decodes step by step (slower). The
validation loss of such a model (``loss`` in eval mode) is computed the same way with a
fixed RNG, so that the best epoch is the one that does best on its own frames.

And ``energy_weight``: a term on the *local speeds* of the expected frames
(sum_k pi_k mu_k) against the reference's over ~1 s windows
(:func:`motionlang.models.seq2seq.losses.energy_loss`, the two-stream model's remedy for
motions that die down to standing). It does not care about phase, only about moving as
much as the reference where the reference moves.

And ``plan_parts`` (:mod:`motionlang.models.seq2seq.plan`): every decoder step also reads a coarse
plan of the motion, its part's mean features and mean absolute change; the true motion's
plan while training, the plan a :class:`motionlang.models.seq2seq.plan.Planner` (its own sentence
encoder, fitted with an MSE term) predicts from the sentence when generating. The decoder
learns to follow the plan, so the sentence steers every frame, not only the first ones.
"""
from __future__ import annotations

from typing import Any

import torch
from torch import nn

from motionlang.errors import MotionlangError
from motionlang.models.frame_losses import energy_loss
from motionlang.models.length import SentenceLength
from motionlang.models.schema import LENGTH_MODEL
from motionlang.models.seq2seq import mdn
from motionlang.models.seq2seq.checkpoint import Seq2SeqCheckpointed
from motionlang.models.seq2seq.config import L2MConfig  # noqa: F401 (re-exported)
from motionlang.models.seq2seq.layers import AdditiveAttention, BiGRUEncoder, StackedDecoder
from motionlang.models.seq2seq.losses import expected_foot_loss
from motionlang.models.seq2seq.plan import Planner, motion_plan, plan_at


class LanguageToMotion(Seq2SeqCheckpointed, nn.Module):
    """Token ids (B, L) -> mixture parameters of every next frame (B, T, ...)."""

    kind = "l2m"
    config_cls = L2MConfig
    input_mask: torch.Tensor | None   # buffers, registered in __init__
    rollout_steps: torch.Tensor

    def __init__(self, config: L2MConfig, vocab: Any = None, normalizer: Any = None,
                 features: Any = None):
        super().__init__()
        c = self.config = config
        if c.loss not in ("surrogate", "exact"):
            raise ValueError(f"L2MConfig.loss must be 'surrogate' or 'exact', not {c.loss!r}")
        if c.loss_weights is not None and (len(c.loss_weights) != c.n_features
                                           or not all(w >= 0 for w in c.loss_weights)):
            raise MotionlangError(f"L2MConfig.loss_weights must be {c.n_features} weights >= 0, "
                                  f"got {len(c.loss_weights)} (min {min(c.loss_weights, default=0)})")
        if c.input_mask is not None and len(c.input_mask) != c.n_features:
            raise MotionlangError(f"L2MConfig.input_mask must have {c.n_features} factors, got "
                                  f"{len(c.input_mask)}")
        if c.rollout_input not in ("sample", "mean"):
            raise MotionlangError(f"L2MConfig.rollout_input must be 'sample' or 'mean', not "
                                  f"{c.rollout_input!r}")
        if not c.input_noise >= 0:
            raise MotionlangError(f"L2MConfig.input_noise must be >= 0, not {c.input_noise!r}")
        if not (c.energy_weight >= 0 and c.energy_window >= 3 and c.energy_window % 2 == 1):
            raise MotionlangError("L2MConfig.energy_weight must be >= 0 and energy_window odd "
                                  f">= 3, got {c.energy_weight!r} and {c.energy_window!r}")
        if c.plan_parts and not c.progress_input:
            raise MotionlangError("L2MConfig.plan_parts needs progress_input (a frame's part "
                                  "of the plan follows from the fraction of the motion done)")
        if not (c.plan_parts >= 0 and c.plan_weight >= 0 and c.plan_noise >= 0):
            raise MotionlangError("L2MConfig.plan_parts, plan_weight and plan_noise must be "
                                  f">= 0, got {c.plan_parts!r}, {c.plan_weight!r}, "
                                  f"{c.plan_noise!r}")
        if c.foot_weight > 0 and features is not None and (
                getattr(features, "kind", None) != "positions" or c.n_features != features.dim):
            raise MotionlangError("L2MConfig.foot_weight needs position features (train l2m "
                                  "--features positions): the foot's step is read from "
                                  "joint positions")
        self.vocab, self.normalizer, self.features = vocab, normalizer, features
        self.embed = nn.Embedding(c.vocab_size, c.embed_dim, padding_idx=c.pad_id)
        self.embed_norm = nn.LayerNorm(c.embed_dim)
        self.drop = nn.Dropout(c.dropout)
        self.encoder = BiGRUEncoder(c.embed_dim, c.enc_hidden, c.enc_layers, c.dropout)
        ctx = self.encoder.out_dim
        extra = int(c.time_input) + int(c.progress_input)
        extra += 2 * c.n_features if c.plan_parts else 0   # the plan's current part
        self.decoder = StackedDecoder(ctx + c.n_features + extra, c.dec_hidden, c.dec_layers,
                                      c.dropout, layer_norm=True)
        head_in = self.decoder.out_dim
        self.attn = None
        if c.attention:
            self.attn = AdditiveAttention(c.dec_hidden, ctx, c.attn_dim)
            head_in += ctx
        self.head = mdn.MixtureDensityHead(head_in, c.n_features, c.n_components)
        if c.plan_mean_mask is not None and len(c.plan_mean_mask) != c.n_features:
            raise MotionlangError(f"L2MConfig.plan_mean_mask must have {c.n_features} factors, "
                                  f"got {len(c.plan_mean_mask)}")
        self.planner = None
        if c.plan_parts:   # sentence -> (parts, 2F): per part, mean features and mean change
            self.planner = Planner.for_config(c)
        if not 0.0 <= c.rollout <= 1.0:
            raise MotionlangError(f"L2MConfig.rollout must be in [0, 1], not {c.rollout!r}")
        # not saved with the weights: it follows from the config
        self.register_buffer("input_mask", None if c.input_mask is None else
                             torch.tensor(c.input_mask, dtype=torch.float32), persistent=False)
        # Training forwards seen so far: drives the rollout ramp and resumes with the weights.
        self.register_buffer("rollout_steps", torch.zeros((), dtype=torch.long))
        self._register_load_state_dict_pre_hook(_default_rollout_steps)
        #: sentence -> planned length (frames), fitted by the trainer; needed by generation
        #: with ``progress_input`` unless the caller gives the length
        self.length_model: SentenceLength | None = None

    def rollout_prob(self) -> float:
        """Current scheduled-sampling probability (0 when ``rollout`` is off)."""
        c = self.config
        if c.rollout <= 0:
            return 0.0
        if c.rollout_warmup <= 0:
            return c.rollout
        return c.rollout * min(1.0, float(self.rollout_steps) / c.rollout_warmup)

    def encode(self, tokens: torch.Tensor, lengths: torch.Tensor,
               n_frames: torch.Tensor | None = None, plan: torch.Tensor | None = None) -> dict:
        """tokens (B, L) long, lengths (B,) -> decoder state dict (batch-first tensors).

        n_frames (B,): each motion's length in frames, needed to decode with
        ``progress_input`` (not for the context alone). plan (B, parts, 2F): the plan the
        decoder follows (``plan_parts`` models); default the one its planner predicts from the
        sentence.
        """
        x = self.drop(self.embed_norm(self.embed(tokens)))
        context, memory, mask = self.encoder(x, lengths)
        h = x.new_zeros(tokens.shape[0], self.config.dec_layers, self.config.dec_hidden)
        state = {"h": h, "context": context, "memory": memory, "mask": mask}
        if self.planner is not None:
            state["plan"] = self.planner(tokens, lengths) if plan is None else plan
        if self.config.progress_input and n_frames is not None:
            state["n_frames"] = torch.as_tensor(n_frames, dtype=x.dtype).reshape(-1)
        return state

    def frames_for(self, sentence: str) -> int | None:
        """The planned length of ``sentence``'s motion (frames), None without a length model."""
        return None if self.length_model is None else self.length_model.frames(sentence)

    def _decode(self, state: dict, prev: torch.Tensor, t0: int = 0
                ) -> tuple[mdn.MixtureParams, torch.Tensor]:
        """prev (B, T, F) previous frames (the first at decoding step ``t0``) -> params with
        leading (B, T), hidden (B, layers, H)."""
        B, T = prev.shape[:2]
        if self.input_mask is not None:   # every path (teacher forcing, rollout, generation)
            prev = prev * self.input_mask
        ctx = state["context"].unsqueeze(1).expand(-1, T, -1)
        inputs = [ctx, prev]
        if self.config.time_input:
            clock = (torch.arange(T, dtype=prev.dtype) + t0) / 100.0
            inputs.append(clock.view(1, T, 1).expand(B, T, 1))
        if self.config.progress_input:
            if "n_frames" not in state:
                raise MotionlangError("this L2M model reads the fraction of its motion done: "
                                      "encode with the motion's length (n_frames)")
            t = torch.arange(T, dtype=prev.dtype) + t0
            done = t.view(1, T) / (state["n_frames"].view(B, 1) - 1).clamp(min=1)
            inputs.append(done.unsqueeze(-1))
        if self.planner is not None:
            t = torch.arange(T) + t0
            inputs.append(plan_at(state["plan"], t, state["n_frames"]).to(prev.dtype))
        outs, h = self.decoder(torch.cat(inputs, dim=-1), state["h"])
        if self.attn is not None:
            att, _ = self.attn(outs[..., -self.config.dec_hidden:], state["memory"],
                               state["mask"])
            outs = torch.cat([outs, att], dim=-1)
        return self.head(outs), h

    def forward(self, tokens: torch.Tensor, token_lengths: torch.Tensor,
                motion: torch.Tensor, motion_lengths: torch.Tensor | None = None,
                return_fed: bool = False):
        """Params of frames 0..T-1 (B, T, ...) given the target motion (B, T, F) (valid
        lengths ``motion_lengths`` (B,), default all T): teacher forced, or while training
        with ``rollout`` on, partly fed the model's own frames. With ``return_fed`` also
        the previous frames the decoder was fed (B, T, F), before ``input_mask``."""
        prev = _previous_frames(motion)
        if self.training and self.config.input_noise > 0:
            prev = prev + self.config.input_noise * torch.randn_like(prev)
        lengths = _lengths(motion, motion_lengths)
        state = self.encode(tokens, token_lengths, lengths, self._true_plan(motion, lengths))
        p = self.rollout_prob() if self.training else 0.0
        if self.training and self.config.rollout > 0:
            self.rollout_steps += 1
        if p <= 0:
            params, _ = self._decode(state, prev)
            fed = prev
        else:
            params, fed = self._rollout(state, prev, p)
        return (params, fed) if return_fed else params

    def rollout_forward(self, tokens: torch.Tensor, token_lengths: torch.Tensor,
                        motion: torch.Tensor, p: float, seed: int = 0,
                        motion_lengths: torch.Tensor | None = None,
                        sentence_plan: bool = False, return_fed: bool = False):
        """Params (B, T, ...) with own-frame probability ``p`` in [0, 1], reproducible (its own
        RNG seeded with ``seed``); no input noise, whatever the mode. A ``plan_parts`` model
        follows the motion's own plan, or with ``sentence_plan`` the one it predicts from
        the sentence (as when generating). ``return_fed`` as for :meth:`forward`."""
        prev = _previous_frames(motion)
        lengths = _lengths(motion, motion_lengths)
        plan = None if sentence_plan else self._true_plan(motion, lengths)
        state = self.encode(tokens, token_lengths, lengths, plan)
        params, fed = self._rollout(state, prev, p, torch.Generator().manual_seed(seed))
        return (params, fed) if return_fed else params

    def plan_target(self, motion: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """The plan (B, parts, 2F) of motions (B, T, F) with valid ``lengths`` (B,), as this
        model plans (``plan_parts``, ``plan_mean_mask``)."""
        c = self.config
        mask = None if c.plan_mean_mask is None else torch.tensor(c.plan_mean_mask)
        return motion_plan(motion, lengths, c.plan_parts, mask)

    def _true_plan(self, motion: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor | None:
        """The plan fed while training (``plan_parts`` models; else None): the motion's own,
        with noise of std ``plan_noise`` in training mode, so that the decoder tolerates a
        predicted plan's errors."""
        if self.planner is None:
            return None
        plan = self.plan_target(motion, lengths)
        if self.training and self.config.plan_noise > 0:
            plan = plan + self.config.plan_noise * torch.randn_like(plan)
        return plan

    def _rollout(self, state: dict, prev: torch.Tensor, p: float,
                 generator: torch.Generator | None = None
                 ) -> tuple[mdn.MixtureParams, torch.Tensor]:
        """Scheduled sampling over prev (B, T, F): params with leading (B, T), and the
        frames fed (B, T, F)."""
        B, T, _ = prev.shape
        steps, fed = [], []
        x = prev[:, 0]
        for t in range(T):
            fed.append(x)
            params, h = self._decode(state, x.unsqueeze(1), t)
            state = {**state, "h": h}
            steps.append(params)
            if t + 1 < T:
                with torch.no_grad():
                    own = (mdn.mixture_mean(params.flatten())
                           if self.config.rollout_input == "mean"
                           else mdn.sample(params.flatten(), 1, generator)[0][:, 0])
                use_own = torch.rand(B, 1, generator=generator) < p
                x = torch.where(use_own, own, prev[:, t + 1])
        return mdn.MixtureParams(*(torch.cat([getattr(s, f) for s in steps], dim=1)
                                   for f in ("logit_pi", "mu", "log_sigma", "active_logit"))
                                 ), torch.stack(fed, dim=1)

    def step(self, state: dict, prev_frames: torch.Tensor) -> tuple[mdn.MixtureParams, dict]:
        """One decoding step: prev_frames (N, F) -> params over N rows, new state."""
        t = state.get("t", 0)
        params, h = self._decode(state, prev_frames.unsqueeze(1), t)
        return params.flatten(), {**state, "h": h, "t": t + 1}

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """batch: ``tokens`` (B, L), ``token_lengths`` (B,), ``motion`` (B, T, F) padded,
        ``motion_lengths`` (B,). Losses are means over valid frames (``energy``: valid frame
        pairs); ``nll`` is the
        frame's negative log density (surrogate or exact; per-feature weighted by
        ``config.loss_weights`` when set), ``active_bce`` the flag's; ``energy`` (with
        ``config.energy_weight`` > 0) the local-speed term of the expected frames, ``mean_sq``
        (with ``config.mean_weight`` > 0) their squared error against the reference, ``plan``
        (with ``config.plan_parts``) the mean squared error of the plan predicted from the
        sentence."""
        motion, lengths = batch["motion"], batch["motion_lengths"]
        B, T, _ = motion.shape
        if not self.training and self.config.rollout > 0:
            # validation of a scheduled-sampling model: as trained at full ramp (a fraction
            # ``rollout`` of its inputs its own frames), with a fixed RNG so that epochs
            # compare; picks best.pt
            params, fed = self.rollout_forward(batch["tokens"], batch["token_lengths"],
                                               motion, self.config.rollout,
                                               motion_lengths=lengths, return_fed=True)
        else:
            params, fed = self(batch["tokens"], batch["token_lengths"], motion, lengths,
                               return_fed=True)
        params = params.flatten()
        t = torch.arange(T).unsqueeze(0)
        valid = (t < lengths.unsqueeze(1)).reshape(-1)
        active = (t < (lengths.unsqueeze(1) - 1)).reshape(-1).float()
        x = motion.reshape(B * T, -1)
        weights = (None if self.config.loss_weights is None
                   else torch.tensor(self.config.loss_weights, dtype=x.dtype, device=x.device))
        log_density = (mdn.surrogate_log_prob if self.config.loss == "surrogate"
                       else mdn.mixture_log_prob)(params, x, weights)
        nll = -log_density[valid].mean()
        # The last frame is the only "stop" example of a motion; end_weight > 1 makes it
        # count more so that generation learns to end (the paper's loss: 1).
        w = torch.where(active > 0, 1.0, self.config.end_weight)[valid]
        bce = -(w * mdn.active_log_prob(params, active)[valid]).sum() / w.sum()
        out = {"loss": nll + bce, "nll": nll.detach(), "active_bce": bce.detach()}
        c = self.config
        # the expected frames (B, T, F): what mean decoding writes, read by the terms below
        mean = (mdn.mixture_mean(params).reshape(B, T, -1)
                if max(c.energy_weight, c.mean_weight, c.foot_weight) > 0 else None)
        if c.energy_weight > 0:
            # the expected frames must move as much as the reference does, wherever the
            # sample of the step before has taken the motion (phase-free, ~1 s windows)
            assert mean is not None
            energy = energy_loss(mean, motion, valid.reshape(B, T).to(motion), c.energy_window)
            out["loss"] = out["loss"] + c.energy_weight * energy
            out["energy"] = energy.detach()
        if c.mean_weight > 0:
            # the frames mean decoding writes must be the reference's (config.mean_weight)
            mean_sq = ((mean - motion) ** 2).sum(-1)[valid.reshape(B, T)].mean()
            out["loss"] = out["loss"] + c.mean_weight * mean_sq
            out["mean_sq"] = mean_sq.detach()
        if c.foot_weight > 0:
            assert mean is not None
            foot = expected_foot_loss(mean, motion, valid.reshape(B, T), fed, self.features,
                                      step=c.foot_step, down=c.foot_down)
            out["loss"] = out["loss"] + c.foot_weight * foot
            out["foot"] = foot.detach()
        if self.planner is not None:
            # the planner that plans from the sentence at generation time (the decoder above
            # was fed the true plan); its parameters are its own
            pred = self.planner(batch["tokens"], batch["token_lengths"])
            plan_mse = ((pred - self.plan_target(motion, lengths)) ** 2).mean()
            out["loss"] = out["loss"] + self.config.plan_weight * plan_mse
            out["plan"] = plan_mse.detach()
        return out

    state_schema = {**Seq2SeqCheckpointed.state_schema, "length_model": LENGTH_MODEL}

    def checkpoint_state(self) -> dict:
        return {**super().checkpoint_state(), "length_model": (
            None if self.length_model is None else self.length_model.to_dict())}

    def restore_state(self, state: dict) -> None:
        if state.get("length_model"):   # checkpoints before it have none
            self.length_model = SentenceLength.from_dict(state["length_model"])


def _lengths(motion: torch.Tensor, lengths: torch.Tensor | None) -> torch.Tensor:
    return torch.full((motion.shape[0],), motion.shape[1]) if lengths is None else lengths


def _default_rollout_steps(state_dict, prefix, *args, **kwargs):
    """Checkpoints written before ``rollout`` existed lack the counter: start it at 0."""
    state_dict.setdefault(prefix + "rollout_steps", torch.zeros((), dtype=torch.long))


def _previous_frames(motion: torch.Tensor) -> torch.Tensor:
    """Decoder inputs of a target motion (B, T, F): a zero frame, then frames 0..T-2."""
    return torch.cat([motion.new_zeros(motion.shape[0], 1, motion.shape[2]), motion[:, :-1]],
                     dim=1)

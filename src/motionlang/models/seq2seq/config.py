"""Configs of the seq2seq models (Plappert, Mandery & Asfour 2018), free of torch.

Kept apart from :mod:`motionlang.models.seq2seq.m2l` / :mod:`motionlang.models.seq2seq.l2m` so that the CLI
can read the default sizes for ``--help`` without importing torch (2-10 s per call).
"""
from __future__ import annotations

from dataclasses import dataclass

from motionlang.errors import MotionlangError
from motionlang.utils.checks import check_numbers


@dataclass
class M2LConfig:
    """Sizes of the motion-to-language model; paper defaults except the data-given ones.

    n_features: per-frame motion feature size F (from the features/dataset, never fixed here).
    vocab_size: V, including PAD/SOS/EOS/UNK at ids ``pad_id``/``sos_id``/``eos_id``/3.
    """

    n_features: int
    vocab_size: int
    enc_hidden: int = 64
    enc_layers: int = 2
    dec_hidden: int = 128
    dec_layers: int = 2
    embed_dim: int = 64
    dropout: float = 0.4
    attention: bool = False
    attn_dim: int = 64
    pad_id: int = 0
    sos_id: int = 1
    eos_id: int = 2
    max_len: int = 40          # decoding cap in tokens, EOS included

    def __post_init__(self):
        check_numbers("M2LConfig", self, unit=("dropout",), positive_ints=(
            "n_features", "vocab_size", "enc_hidden", "enc_layers", "dec_hidden",
            "dec_layers", "embed_dim", "attn_dim", "max_len"))


@dataclass
class L2MConfig:
    """Sizes of the language-to-motion model; paper defaults except the data-given ones.

    vocab_size: V (from the vocabulary); n_features: per-frame feature size F (from data).
    """

    vocab_size: int
    n_features: int
    embed_dim: int = 64
    enc_hidden: int = 64
    enc_layers: int = 2
    dec_hidden: int = 400
    dec_layers: int = 3
    n_components: int = 20
    dropout: float = 0.1
    attention: bool = False
    attn_dim: int = 64
    loss: str = "surrogate"     # or "exact"
    end_weight: float = 1.0     # BCE weight of a motion's last frame (1 = the paper's loss)
    input_noise: float = 0.0    # std of noise on the teacher-forced previous frames (0 = paper)
    time_input: bool = False    # decoder also sees the elapsed time (frames / 100) (not in paper)
    # decoder also sees the fraction of the motion done, t / (T - 1), for a length T that is
    # the true one in training and planned from the sentence in generation (not in paper)
    progress_input: bool = False
    rollout: float = 0.0        # scheduled sampling: P(feed own sampled frame) while training
    rollout_warmup: int = 0     # optimiser steps over which that probability ramps up from 0
    # what "its own frame" is: a draw from the mixture ("sample") or its expected frame
    # sum_k pi_k mu_k ("mean"; such a model generates with mean decoding of that frame)
    rollout_input: str = "sample"
    # per-feature weights of the frame NLL (length n_features; None = all 1, the paper's):
    # e.g. the root's ground velocity made to count more (train l2m --root-weight)
    loss_weights: list[float] | None = None
    # per-feature factors on the previous frames the decoder reads (length n_features; None =
    # all 1, the paper's): 0 hides a feature from the input but still predicts it, e.g. the
    # root's ground velocity and heading change (train l2m --hide-root-input), so that the
    # way the body goes cannot be copied from the frame before and must come from the
    # sentence and the body's own movement
    input_mask: list[float] | None = None
    # weight of a term on the local speeds of the expected frames (sum_k pi_k mu_k) against
    # the reference's (``sequence_losses.energy_loss``, window ``energy_window`` frames, ~1 s
    # at 10 Hz); 0 = off (the paper's loss). Beyond the paper, as for the two-stream model.
    energy_weight: float = 0.0
    energy_window: int = 11
    # a coarse plan fed to every decoder step (``models.seq2seq.plan``; 0 = off, the paper's): per
    # part of ``plan_parts`` of the motion's duration, each feature's mean and mean absolute
    # change. Training feeds the true motion's plan (plus Gaussian noise of std
    # ``plan_noise``) and fits a planner (its own sentence encoder, ``plan_hidden`` units
    # per direction) to it (MSE, weight ``plan_weight``); generation feeds the planner's
    # plan. Needs ``progress_input``.
    plan_parts: int = 0
    plan_hidden: int = 128
    # per feature, 1 = its mean is in the plan, 0 = not (only its change); None = all
    plan_mean_mask: list[float] | None = None
    plan_weight: float = 1.0
    plan_noise: float = 0.0
    # weight of a term on the expected frames' toe speed (m/s) over the frame steps where a
    # toe is down, the reference's or their own (foot_down; ``losses.foot_contact_loss``;
    # position features only); 0 = off (the paper's loss). Beyond the paper: planted feet.
    foot_weight: float = 0.0
    # which step of a toe that term measures: between consecutive expected frames
    # ("expected"), or from the frame fed to the decoder to the expected frame it gives
    # ("input"). Generation continues from expected frames only for rollout_input "mean"
    # models; the others write the heaviest component's mean (``mdn.mode_frame``)
    foot_step: str = "expected"
    # whose toe says it is down for that term: the reference's, or the expected frames' own
    # (below 5 cm and slower than 1 m/s in them), for a model fed its own frames, whose steps
    # drift out of step with the reference's
    foot_down: str = "reference"
    # weight of a squared error of the expected frames (sum_k pi_k mu_k) against the
    # reference, summed over the normalised features, mean over frames; 0 = off (the paper's
    # loss). Beyond the paper: the surrogate NLL moves a component's mean by pi_k (x -
    # mu_k) / sigma_k^2, so where a broad component has taken a feature (sigma of 3-5 std on
    # the raised arm of a procedural wave) its mean stays at rest and mean decoding never
    # starts the gesture; this term's gradient does not shrink with sigma. Every feature
    # counts alike here, whatever loss_weights gives the NLL
    mean_weight: float = 0.0
    pad_id: int = 0
    max_frames: int = 300       # decoding cap (frames)

    def __post_init__(self):
        check_numbers("L2MConfig", self, unit=("dropout",), positive_ints=(
            "vocab_size", "n_features", "embed_dim", "enc_hidden", "enc_layers", "dec_hidden",
            "dec_layers", "n_components", "attn_dim", "max_frames", "energy_window",
            "plan_hidden"), nonneg_ints=("rollout_warmup", "plan_parts"),
            nonneg=("end_weight", "input_noise", "energy_weight", "plan_weight", "plan_noise",
                    "foot_weight", "mean_weight"))
        if not 0 <= self.rollout <= 1:
            raise MotionlangError(f"L2MConfig.rollout must be in [0, 1], got {self.rollout!r}")
        if self.foot_step not in ("expected", "input"):
            raise MotionlangError(f"L2MConfig.foot_step must be 'expected' or 'input', not "
                                  f"{self.foot_step!r}")
        if self.foot_down not in ("reference", "own"):
            raise MotionlangError(f"L2MConfig.foot_down must be 'reference' or 'own', not "
                                  f"{self.foot_down!r}")
        if self.foot_down == "own" and self.foot_step == "input":
            raise MotionlangError("L2MConfig.foot_down 'own' measures consecutive expected "
                                  "frames: it needs foot_step 'expected'")


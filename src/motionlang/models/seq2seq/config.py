"""Configs of the seq2seq models (Plappert, Mandery & Asfour 2018), free of torch.

Kept apart from :mod:`motionlang.models.seq2seq.m2l` / :mod:`motionlang.models.seq2seq.l2m` so that the CLI
can read the default sizes for ``--help`` without importing torch (seconds on every call).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from motionlang.errors import MotionlangError
from motionlang.utils.checks import MAX_WIDTH, check_numbers


def _opt(default, help_: str, **meta):
    """A field that is also a ``train`` option (``cli.config_options``)."""
    return field(default=default, metadata={"help": help_, **meta})


#: the help of the size options both models share
_SIZES = {"enc_hidden": "encoder LSTM units", "enc_layers": "encoder LSTM layers",
          "dec_hidden": "decoder LSTM units", "dec_layers": "decoder LSTM layers",
          "embed_dim": "word embedding size", "dropout": "dropout between LSTM layers",
          "attention": "additive attention variant"}


def _check_ids(owner: str, cfg, names: tuple[str, ...]) -> None:
    """Special token ids inside the vocabulary (an embedding row each)."""
    for name in names:
        v = getattr(cfg, name)
        if not (isinstance(v, int) and not isinstance(v, bool) and 0 <= v < cfg.vocab_size):
            raise MotionlangError(f"{owner}.{name} must be a token id in 0..{cfg.vocab_size - 1}"
                                  f", got {v!r}")


@dataclass
class M2LConfig:
    """Sizes of the motion-to-language model; paper defaults except the data-given ones.

    n_features: per-frame motion feature size F (from the features/dataset, never fixed here).
    vocab_size: V, including PAD/SOS/EOS/UNK at ids ``pad_id``/``sos_id``/``eos_id``/3.
    """

    n_features: int
    vocab_size: int
    enc_hidden: int = _opt(64, _SIZES["enc_hidden"])
    enc_layers: int = _opt(2, _SIZES["enc_layers"])
    dec_hidden: int = _opt(128, _SIZES["dec_hidden"])
    dec_layers: int = _opt(2, _SIZES["dec_layers"])
    embed_dim: int = _opt(64, _SIZES["embed_dim"])
    dropout: float = _opt(0.4, _SIZES["dropout"])
    attention: bool = _opt(False, _SIZES["attention"])
    attn_dim: int = 64
    pad_id: int = 0
    sos_id: int = 1
    eos_id: int = 2
    max_len: int = 40          # decoding cap in tokens, EOS included

    def __post_init__(self):
        check_numbers("M2LConfig", self, unit=("dropout",), positive_ints=("max_len",),
            dims=("n_features",), vocab=("vocab_size",), sizes=("enc_hidden", "dec_hidden",
                                                           "embed_dim", "attn_dim"),
            layers=("enc_layers", "dec_layers"))
        _check_ids("M2LConfig", self, ("pad_id", "sos_id", "eos_id"))


@dataclass
class L2MConfig:
    """Sizes of the language-to-motion model; paper defaults except the data-given ones.

    vocab_size: V (from the vocabulary); n_features: per-frame feature size F (from data).
    """

    vocab_size: int
    n_features: int
    embed_dim: int = _opt(64, _SIZES["embed_dim"])
    enc_hidden: int = _opt(64, _SIZES["enc_hidden"])
    enc_layers: int = _opt(2, _SIZES["enc_layers"])
    dec_hidden: int = _opt(400, _SIZES["dec_hidden"])
    dec_layers: int = _opt(3, _SIZES["dec_layers"])
    n_components: int = _opt(20, "Gaussian components of the output mixture per frame",
                             flag="--components")
    dropout: float = _opt(0.1, _SIZES["dropout"])
    attention: bool = _opt(False, _SIZES["attention"])
    attn_dim: int = 64
    loss: str = _opt("surrogate", "mixture NLL: the paper's surrogate or the exact one",
                     choices=("surrogate", "exact"))
    end_weight: float = _opt(1.0, "BCE weight of each motion's last (stop) frame (paper: 1)")
    input_noise: float = _opt(0.0, "std of noise on teacher-forced previous frames (paper: 0)")
    time_input: bool = _opt(False, "decoder also sees the elapsed time, frames / 100 (not "
                                   "in the paper)")
    # the length T is the true one in training and planned from the sentence in generation
    progress_input: bool = _opt(False, "decoder also sees the fraction of the motion done, "
                                       "t / (T - 1); generation plans the length from the "
                                       "sentence (not in the paper)")
    rollout: float = _opt(0.0, "scheduled sampling: while training, feed the model's own "
                               "sampled frame instead of the true one with probability P "
                               "(paper: 0)", metavar="P")
    rollout_warmup: int = _opt(0, "optimiser steps over which that probability ramps up "
                                  "from 0", metavar="STEPS")
    # a model fed its expected frames generates with mean decoding of that frame
    rollout_input: str = _opt("sample", "own frame fed back: a draw from the mixture, or its "
                                        "expected frame sum_k pi_k mu_k (then generate with "
                                        "method mean)", choices=("sample", "mean"))
    # per-feature weights of the frame NLL (length n_features; None = all 1, the paper's):
    # set by the recipe from --root-weight
    loss_weights: list[float] | None = None
    # per-feature factors on the previous frames the decoder reads (length n_features; None =
    # all 1, the paper's): 0 hides a feature from the input but still predicts it, so that
    # the way the body goes cannot be copied from the frame before and must come from the
    # sentence and the body's own movement (the recipe's --hide-root-input)
    input_mask: list[float] | None = None
    # beyond the paper, as for the two-stream model: ``losses.energy_loss``
    energy_weight: float = _opt(0.0, "weight of a loss on the local speeds of the expected "
                                     "frames against the reference's, over windows of "
                                     "energy_window frames (paper: 0)", flag="--energy",
                                metavar="W")
    energy_window: int = 11
    # the plan (``models.seq2seq.plan``): per part of ``plan_parts`` of the motion's
    # duration, each feature's mean and mean absolute change; training feeds the true plan
    # plus noise and fits a planner (its own sentence encoder, ``plan_hidden`` units per
    # direction) to it; generation feeds the planner's plan
    plan_parts: int = _opt(0, "feed every decoder step a coarse plan of the motion (per part "
                              "of K of its duration: mean features and mean change), the "
                              "true one in training, one predicted from the sentence when "
                              "generating; needs --progress-input (0: off, the paper's)",
                           metavar="K")
    plan_hidden: int = 128
    # per feature, 1 = its mean is in the plan, 0 = not (only its change); None = all
    plan_mean_mask: list[float] | None = None
    plan_weight: float = _opt(1.0, "weight of the plan head's mean squared error", metavar="W")
    plan_noise: float = _opt(0.0, "std of Gaussian noise on the true plan fed while training",
                             metavar="STD")
    # beyond the paper, planted feet: ``losses.foot_contact_loss``
    foot_weight: float = _opt(0.0, "weight of a loss on the expected frames' toe speed (m/s) "
                                   "where the toe is down (below 5 cm, slower than 1 m/s): "
                                   "planted feet that do not slide; positions features only "
                                   "(paper: 0)", flag="--foot-contact", metavar="W")
    # generation continues from expected frames only for rollout_input "mean" models; the
    # others write the heaviest component's mean (``mdn.mode_frame``)
    foot_step: str = _opt("expected", "the toe step --foot-contact measures: between "
                                      "consecutive expected frames, or from the frame fed "
                                      "to the decoder to the expected frame it gives (the "
                                      "step generation takes)", choices=("expected", "input"))
    # "own": for a model fed its own frames, whose steps drift out of step with the
    # reference's
    foot_down: str = _opt("reference", "whose toe says a foot is down for --foot-contact: "
                                       "the reference's, or the expected frames' own",
                          choices=("reference", "own"))
    # the surrogate NLL moves a component's mean by pi_k (x - mu_k) / sigma_k^2, so where a
    # broad component has taken a feature its mean stays at rest and mean decoding never
    # starts the gesture; this term's gradient does not shrink with sigma. Every feature
    # counts alike here, whatever loss_weights gives the NLL
    mean_weight: float = _opt(0.0, "weight of a squared error of the expected frames against "
                                   "the reference (normalised features): what method mean "
                                   "writes (paper: 0)", flag="--mean-frames", metavar="W")
    pad_id: int = 0
    max_frames: int = 300       # decoding cap (frames)

    def __post_init__(self):
        check_numbers("L2MConfig", self, unit=("dropout",), positive_ints=(
            "max_frames", "energy_window"), dims=("n_features",), vocab=("vocab_size",),
            sizes=("embed_dim", "enc_hidden", "dec_hidden", "n_components", "attn_dim",
                   "plan_hidden"), layers=("enc_layers", "dec_layers"),
            nonneg_ints=("rollout_warmup", "plan_parts"),
            nonneg=("end_weight", "input_noise", "energy_weight", "plan_weight", "plan_noise",
                    "foot_weight", "mean_weight"))
        _check_ids("L2MConfig", self, ("pad_id",))
        if not 0 <= self.rollout <= 1:
            raise MotionlangError(f"L2MConfig.rollout must be in [0, 1], got {self.rollout!r}")
        if self.foot_step not in ("expected", "input"):
            raise MotionlangError(f"L2MConfig.foot_step must be 'expected' or 'input', not "
                                  f"{self.foot_step!r}")
        if self.foot_down not in ("reference", "own"):
            raise MotionlangError(f"L2MConfig.foot_down must be 'reference' or 'own', not "
                                  f"{self.foot_down!r}")
        if not self.plan_parts and (self.plan_weight != 1.0 or self.plan_noise != 0.0):
            raise MotionlangError("L2MConfig.plan_weight and plan_noise apply to a plan: set "
                                  "L2MConfig.plan_parts too")
        if self.plan_parts and not self.progress_input:
            raise MotionlangError("L2MConfig.plan_parts needs L2MConfig.progress_input")
        if self.foot_down == "own" and self.foot_step == "input":
            raise MotionlangError("L2MConfig.foot_down own measures consecutive expected "
                                  "frames: it cannot be used with L2MConfig.foot_step input")
        for name, default in (("foot_step", "expected"), ("foot_down", "reference")):
            if getattr(self, name) != default and not self.foot_weight > 0:
                raise MotionlangError(f"L2MConfig.{name} says how L2MConfig.foot_weight "
                                      f"measures: give L2MConfig.foot_weight > 0 with it")


@dataclass
class L2MOptions:
    """How an L2M samples: ``--model l2m:method=sample,width=5``, the flags of
    ``motionlang generate`` (generated from the fields with a help text) or the keywords of
    ``ml.generate``; one default each, here.

    Attributes:
        method: "sample" (ancestral), "beam" (the paper's sampled beam) or "mean" (the
            mixture's expected frames); None: the model's own way for ``generate``, "mean"
            for evaluation rows.
        width: samples (or beam width) per sentence; the likeliest is kept (or, with
            ``rerank``, the one that M2L finds the sentence likeliest for); mean decoding
            gives one motion.
        temperature: sharpen the mixture when sampling (1: as trained).
        rerank: an M2L (packaged name, file or run folder) ranking the ``width`` motions.
        length_norm: rank hypotheses by log likelihood per frame.
        map_words: read a word its vocabulary lacks as the nearest known word
            (``models.word_map.WordOptions``; ``generate`` prints what it read as what);
            false: as one unknown-word token.
    """

    method: str | None = _opt(
        None, "W ancestral samples, the paper's sampled beam (ranked by likelihood, it "
        "favours standing still), or the mixture's expected frames (default: the model's "
        "own way: mean for models trained on their expected frames or on joint positions, "
        "such as the packaged L2M; sample for joint-angle models)",
        choices=("sample", "beam", "mean"))
    width: int = _opt(1, "hypotheses: samples or beam width, written likeliest first "
                         "(sample, beam)", aliases=("-w",), metavar="W")
    temperature: float = _opt(1.0, "sample (beam, sample) from the mixture sharpened by "
                                   "TAU: weights softmax(logits / TAU), deviations x TAU; "
                                   "1 samples as trained", metavar="TAU")
    rerank: str | None = _opt(None, "rank the W motions by this M2L model's log P(text | "
                                    "motion) instead of their own likelihood (sample or "
                                    "beam)", metavar="M2L")
    length_norm: bool = _opt(False, "rank hypotheses (beam, sample) by log likelihood per "
                                    "frame, not in total")
    map_words: bool = True

    def __post_init__(self) -> None:
        if self.method not in (None, "sample", "beam", "mean"):
            raise ValueError(f"method must be sample, beam or mean, got {self.method!r}")
        if isinstance(self.width, bool) or not 1 <= int(self.width) <= MAX_WIDTH:
            raise ValueError(f"width must be an integer in 1..{MAX_WIDTH}, got {self.width}")
        if not (math.isfinite(self.temperature) and self.temperature > 0):
            raise ValueError(f"temperature must be a finite number > 0, got {self.temperature}")
        if self.method == "mean" and self.width != 1:
            raise ValueError("width applies to 'sample' and 'beam'; mean decoding gives one "
                             "motion")
        if self.method == "mean" and self.temperature != 1.0:
            raise ValueError("temperature applies to 'sample' and 'beam'; mean decoding "
                             "draws nothing")
        if self.rerank and (self.method == "mean" or self.width < 2):
            raise ValueError("rerank ranks several motions: method sample or beam "
                             "with width 2 or more")

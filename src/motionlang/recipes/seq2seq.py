"""The recipe of the seq2seq models (Plappert et al. 2018): ``--data`` sources -> (motion,
sentence) pairs (``datasets.seq2seq_pairs``) -> an M2L or L2M -> the shared trainer ->
``model.pt`` (the best checkpoint by validation loss).

Several sources are mixed by their ``@W`` weights (``datasets.mixing``); a run trained on a
non-commercial source gets the licence file. Everything that can be checked is checked
before the (long) data preparation, and nothing is written before the data is read.
"""
from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.datasets.mixing import mix_training
from motionlang.datasets.seq2seq_pairs import (
    balance_repeats,
    build_pairs,
    oversample,
    sentence_lengths,
)
from motionlang.datasets.text import SPECIALS
from motionlang.errors import MotionlangError
from motionlang.features.frames import model_dim
from motionlang.models.length import SentenceLength
from motionlang.models.registry import family
from motionlang.models.seq2seq.config import L2MConfig, M2LConfig
from motionlang.recipes import Recipe
from motionlang.training.run_steps import begin_run, finish_run
from motionlang.utils.checks import check_numbers

#: the root's ground velocity and heading change among the features
ROOT_MOTION = ("root_vx", "root_vz", "root_dyaw")
log = logging.getLogger(__name__)


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class Seq2SeqData:
    """The data options of ``train m2l`` / ``train l2m`` (the recipe's, not the model's)."""

    features: str = _opt("angles", "angles: the 44 MMM joint angles (KIT MMM motions only); "
                                   "positions: the 21-joint body (any rig that maps onto it)",
                         choices=("angles", "positions"))
    joint_map: str | None = _opt(None, "how a custom folder's rig maps onto the 21-joint body "
                                       "(default: joint_map.json in the folder, else chosen "
                                       "by joint names)", metavar="MAP.json")
    offsets: int = _opt(10, "down-sampling start offsets per motion (augmentation)")
    max_seconds: float = _opt(30.0, "drop longer motions")
    min_count: int = _opt(1, "vocabulary: minimum word count")
    mirror: bool = _opt(False, "also train on every training motion mirrored left/right, its "
                               "sentences' left and right swapped (with --balance a mirrored "
                               "copy is repeated as often as its original)")
    balance: int = _opt(1, "repeat training motions with rare ground-truth primitives (e.g. "
                           "walking backwards) up to MAX times per epoch; needs a procedural "
                           "corpus (1: off)", metavar="MAX")

    def __post_init__(self) -> None:
        check_numbers(type(self).__name__, self, positive_ints=("offsets", "min_count",
                                                               "balance"),
                      positive=("max_seconds",))
        if self.features not in ("angles", "positions"):
            raise MotionlangError(f"{type(self).__name__}.features must be angles or "
                                  f"positions, got {self.features!r}")


@dataclass
class L2MData(Seq2SeqData):
    """The data options of ``train l2m``: those of the M2L and what the L2M derives from
    the features (weights and masks of the root's values)."""

    root_weight: float = _opt(1.0, "weight of the root's ground velocity and heading change "
                                   "(root_vx, root_vz, root_dyaw) in the frame NLL (paper: 1)",
                              metavar="W")
    hide_root_input: bool = _opt(False, "the decoder does not read the previous frame's root "
                                        "velocity and heading change (it still predicts them; "
                                        "not in the paper)")
    plan_means: str = _opt("all", "which features' part means the plan holds: all, or only "
                                  "the root's ground velocity and heading change (every "
                                  "feature's change is in it either way)",
                           choices=("all", "root"))

    def __post_init__(self) -> None:
        super().__post_init__()
        check_numbers("L2MData", self, nonneg=("root_weight",))
        if self.plan_means not in ("all", "root"):
            raise MotionlangError(f"L2MData.plan_means must be all or root, got "
                                  f"{self.plan_means!r}")


def root_loss_weights(features, weight: float, option: str = "--root-weight") -> list[float]:
    """Per-feature factors: ``weight`` for the root's ground velocity and heading change
    (:data:`ROOT_MOTION`), 1 elsewhere, over the model's features (active flag excluded):
    NLL weights, and with weight 0 the input mask of ``hide_root_input``."""
    names = list(features.names)[:model_dim(features)]
    missing = [n for n in ROOT_MOTION if n not in names]
    if missing:
        raise MotionlangError(f"{option} needs features with {', '.join(ROOT_MOTION)} "
                              f"(angles with the root trajectory, or positions); these have no "
                              f"{', '.join(missing)}")
    return [weight if n in ROOT_MOTION else 1.0 for n in names]


def check_mixed_features(sources: Sequence, features: str) -> None:
    """Several datasets meet only on the 21-joint body: angle features are MMM's alone."""
    if len(sources) > 1 and features == "angles":
        raise MotionlangError("--features angles are KIT MMM joint angles, which mixed "
                              "datasets do not share: use --features positions with several "
                              "--data")


def _config_check(kind: str, model_cfg: dict) -> None:
    """The model options checked by the config itself before any data is read."""
    # the smallest sizes the data could give: one feature, the special tokens
    (M2LConfig if kind == "m2l" else L2MConfig)(1, len(SPECIALS), **model_cfg)


def new_model(kind: str, model_cfg: dict, data, data_cfg: Seq2SeqData, seed: int):
    """A fresh M2L or L2M for ``data`` (``seq2seq_pairs.build_pairs``) with the user's
    config fields, seeded; an L2M told its progress gets its length model fitted on the
    training pairs."""
    import torch

    torch.manual_seed(seed)
    F, V = model_dim(data.features), len(data.vocab)
    if kind == "m2l":
        from motionlang.models.seq2seq.m2l import M2LConfig, MotionToLanguage
        return MotionToLanguage(M2LConfig(n_features=F, vocab_size=V, **model_cfg),
                                data.vocab, features=data.features)
    from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
    derived: dict[str, Any] = {}
    if not isinstance(data_cfg, L2MData):
        data_cfg = L2MData(**vars(data_cfg))
    if data_cfg.root_weight != 1.0:
        derived["loss_weights"] = root_loss_weights(data.features, data_cfg.root_weight)
    if data_cfg.hide_root_input:
        derived["input_mask"] = root_loss_weights(data.features, 0.0, "--hide-root-input")
    if model_cfg.get("plan_parts") and data_cfg.plan_means == "root":
        derived["plan_mean_mask"] = [1.0 - w for w in root_loss_weights(
            data.features, 0.0, "--plan-means root")]
    longest = max(len(it["motion"]) for it in data.items["train"])
    model = LanguageToMotion(L2MConfig(vocab_size=V, n_features=F,
                                       max_frames=int(1.5 * longest),
                                       **{**model_cfg, **derived}),
                             data.vocab, features=data.features)
    if model.config.progress_input:   # it plans its length from the sentence
        model.length_model = SentenceLength.fit(*sentence_lengths(data, "train"))
    return model


def run(kind: str, sources: Sequence, out: Path, model_cfg: dict, train_cfg,
        data_cfg: Seq2SeqData, *, resume: bool = False, options: dict | None = None) -> Path:
    """Train an M2L or L2M (``kind``) into the run folder ``out``; ``options``: what to
    log in ``commands.jsonl`` (default: the configs). Returns ``out/model.pt``."""
    from motionlang.training.collate import collate_pairs
    from motionlang.training.run_files import check_resume_data
    from motionlang.training.trainer import Trainer

    out = Path(out)
    check_mixed_features(sources, data_cfg.features)
    _config_check(kind, model_cfg)
    # one line per epoch from the trainer (the progress bar only shows on a terminal)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    data = build_pairs(list(sources), features=data_cfg.features, offsets=data_cfg.offsets,
                       seed=train_cfg.seed, min_count=data_cfg.min_count,
                       max_seconds=data_cfg.max_seconds, mirror=data_cfg.mirror,
                       joint_map=data_cfg.joint_map)
    train_items = data.items["train"]
    if data_cfg.balance > 1:
        repeats = balance_repeats(data.labels, data.splits["train"], data_cfg.balance)
        train_items = oversample(train_items, repeats)
        print(f"balanced: {len(data.items['train'])} -> {len(train_items)} training pairs "
              f"(motions repeated up to {data_cfg.balance} times)")
    train_items = mix_training(sources, train_items, data.sources, train_cfg.seed)
    model = new_model(kind, model_cfg, data, data_cfg, train_cfg.seed)   # checks root options
    if resume:   # the run's vocabulary and features, checked before anything is written
        check_resume_data(out, model)
    note = begin_run(out, sources=sources, what=kind.upper(), splits=data.splits,
                     resume=resume, options=options,
                     logged={"model": kind, "data": [str(s) for s in sources],
                             "resume": resume, **model_cfg, **vars(data_cfg),
                             **vars(train_cfg)})
    print(f"{kind}: {len(train_items)} training pairs ({len(data.splits['train'])} motions), "
          f"vocabulary {len(data.vocab)}, {model_dim(data.features)} features/frame, "
          f"{sum(p.numel() for p in model.parameters()):,} parameters")
    trainer = Trainer(model, train_items, collate_pairs, train_cfg,
                      val_set=data.items.get("val") or None)
    history = trainer.fit(resume=resume)
    path = out / family(kind).model_file
    final = model
    if trainer.rank == 0:
        best = out / "best.pt"
        # without validation "best" is the lowest training loss, which scheduled sampling
        # raises as it ramps up: then the final weights are the model
        by_train_loss = not data.items.get("val") and getattr(model.config, "rollout", 0) > 0
        final = type(model).load(best) if best.exists() and not by_train_loss else model
    last = history[-1] if history else {}
    return finish_run(path, final, lambda: f"{path}: epoch {last.get('epoch')}, train "
                                           f"{last.get('train')}, val {last.get('val')}", note)


def _run_m2l(*args: Any, **kw: Any) -> Path:
    return run("m2l", *args, **kw)


def _run_l2m(*args: Any, **kw: Any) -> Path:
    return run("l2m", *args, **kw)


#: data options that change what an epoch trains on, never the vocabulary or the split
RESUMABLE = ("offsets", "mirror", "balance")
M2L = Recipe(run=_run_m2l, data_config=Seq2SeqData, train_defaults={"epochs": 20},
             resume_may_change=RESUMABLE)
L2M = Recipe(run=_run_l2m, data_config=L2MData,
             train_defaults={"epochs": 20, "grad_clip": 25.0},
             resume_may_change=(*RESUMABLE, "root_weight", "hide_root_input", "plan_means"))

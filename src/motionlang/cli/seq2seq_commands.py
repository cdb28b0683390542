"""``motionlang train m2l|l2m`` (``evaluate`` is :mod:`motionlang.cli.evaluate_commands`;
``describe`` and ``generate`` live in :mod:`motionlang.cli.text_commands`).

Thin wrappers over :mod:`motionlang.datasets.seq2seq_pairs` (dataset -> pairs),
:class:`motionlang.training.trainer.Trainer` and :mod:`motionlang.decoding.seq2seq`.
``--data`` is a KIT-ML-format folder (the release, or a procedural corpus), a custom
folder of motion files with ``captions.csv``/``captions.jsonl``, or a prefixed folder
(``bandai:``, ``humanml3d:``, ``kitml-h3d:``); given several times, with optional
``@WEIGHT`` shares of each epoch (``datasets.mixing``).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from motionlang.cli.options import (
    dropout_float,
    layers_int,
    nonneg_float,
    nonneg_int,
    positive_float,
    positive_int,
    probability,
    size_int,
)
from motionlang.cli.run_log import lead_process, log_command
from motionlang.cli.train_commands import MODEL_FILES, add_out_arg, add_trainer_args, train_config
from motionlang.errors import MotionlangError


# ------------------------------------------------------------------ train m2l | l2m
def add_data_arg(p: argparse.ArgumentParser, shared: str = "") -> None:
    """The repeatable ``--data DIR[@W]`` of the trainers that mix datasets."""
    p.add_argument("--data", required=True, action="append", type=data_source,
                   metavar="DIR[@W]",
                   help="KIT-ML-format or custom folder, or bandai:DIR / humanml3d:DIR / "
                        "kitml-h3d:DIR; repeat it to train on several datasets at once (one "
                        f"vocabulary, {shared}each dataset's own split). DIR@W "
                        "weights a dataset: it fills W / (sum of the weights) of every epoch, "
                        "its pairs repeated or a seeded subset of them left out (epoch size: "
                        "all datasets' training pairs); weight every dataset or none (none: "
                        "every pair once). E.g. --data corpus@1 --data bandai:DIR@1")


def _add_train(sub, name: str, help_: str) -> None:
    # torch-free config module: building the parser must not import torch
    from motionlang.models.seq2seq.config import L2MConfig, M2LConfig
    d = M2LConfig(1, 1) if name == "m2l" else L2MConfig(1, 1)
    p = sub.add_parser(name, help=help_, description=help_)
    add_data_arg(p, "--features positions, ")
    add_out_arg(p, name, "best.pt and last.pt (checkpoints), history.json, "
                         "loss_curve.png, splits/, ")
    p.add_argument("--features", choices=("angles", "positions"), default="angles",
                   help="angles: the 44 MMM joint angles (KIT MMM motions only); positions: "
                        "the 21-joint body (any rig that maps onto it)")
    p.add_argument("--joint-map", metavar="MAP.json", default=None,
                   help="how a custom folder's rig maps onto the 21-joint body (default: "
                        "joint_map.json in the folder, else chosen by joint names)")
    p.add_argument("--offsets", type=positive_int, default=10,
                   help="down-sampling start offsets per motion (augmentation)")
    p.add_argument("--max-seconds", type=positive_float, default=30.0, help="drop longer motions")
    p.add_argument("--min-count", type=positive_int, default=1,
                   help="vocabulary: minimum word count")
    add_trainer_args(p, epochs=20, grad_clip=None if name == "m2l" else 25.0)
    p.add_argument("--enc-hidden", type=size_int, default=d.enc_hidden,
                   help="encoder LSTM units")
    p.add_argument("--enc-layers", type=layers_int, default=d.enc_layers,
                   help="encoder LSTM layers")
    p.add_argument("--dec-hidden", type=size_int, default=d.dec_hidden,
                   help="decoder LSTM units")
    p.add_argument("--dec-layers", type=layers_int, default=d.dec_layers,
                   help="decoder LSTM layers")
    p.add_argument("--embed-dim", type=size_int, default=d.embed_dim,
                   help="word embedding size")
    p.add_argument("--dropout", type=dropout_float, default=d.dropout,
                   help="dropout between LSTM layers")
    p.add_argument("--attention", action="store_true", help="additive attention variant")
    p.add_argument("--mirror", action="store_true",
                   help="also train on every training motion mirrored left/right, its "
                        "sentences' left and right swapped (with --balance a mirrored copy "
                        "is repeated as often as its original)")
    p.add_argument("--balance", type=positive_int, default=1, metavar="MAX",
                   help="repeat training motions with rare ground-truth primitives (e.g. "
                        "walking backwards) up to MAX times per epoch; needs a procedural "
                        "corpus (default 1: off)")
    if name == "l2m":
        p.add_argument("--components", type=size_int, default=d.n_components,
                       help="Gaussian components of the output mixture per frame")
        p.add_argument("--loss", choices=("surrogate", "exact"), default=d.loss,
                       help="mixture NLL: the paper's surrogate or the exact one")
        p.add_argument("--end-weight", type=nonneg_float, default=d.end_weight,
                       help="BCE weight of each motion's last (stop) frame (paper: 1)")
        p.add_argument("--input-noise", type=nonneg_float, default=d.input_noise,
                       help="std of noise on teacher-forced previous frames (paper: 0)")
        p.add_argument("--time-input", action="store_true",
                       help="decoder also sees the elapsed time (not in the paper)")
        p.add_argument("--progress-input", action="store_true",
                       help="decoder also sees the fraction of the motion done; generation "
                            "plans the length from the sentence (not in the paper)")
        p.add_argument("--rollout", type=probability, default=d.rollout, metavar="P",
                       help="scheduled sampling: while training, feed the model's own sampled "
                            "frame instead of the true one with probability P (paper: 0)")
        p.add_argument("--root-weight", type=nonneg_float, default=1.0, metavar="W",
                       help="weight of the root's ground velocity and heading change "
                            "(root_vx, root_vz, root_dyaw) in the frame NLL (paper: 1)")
        p.add_argument("--hide-root-input", action="store_true",
                       help="the decoder does not read the previous frame's root velocity and "
                            "heading change (it still predicts them; not in the paper)")
        p.add_argument("--rollout-warmup", type=nonneg_int, default=d.rollout_warmup,
                       metavar="STEPS",
                       help="optimiser steps over which that probability ramps up from 0")
        p.add_argument("--rollout-input", choices=("sample", "mean"), default=d.rollout_input,
                       help="own frame fed back: a draw from the mixture, or its expected "
                            "frame (then generate with --method mean)")
        p.add_argument("--energy", type=nonneg_float, default=d.energy_weight, metavar="W",
                       help="weight of a loss on the local speeds of the expected frames "
                            "against the reference's, over ~1 s windows (paper: 0)")
        p.add_argument("--mean-frames", type=nonneg_float, default=d.mean_weight, metavar="W",
                       help="weight of a squared error of the expected frames against the "
                            "reference (normalised features): what --method mean writes "
                            "(paper: 0)")
        p.add_argument("--foot-contact", type=nonneg_float, default=d.foot_weight,
                       metavar="W",
                       help="weight of a loss on the expected frames' toe speed (m/s) where "
                            "the reference's toe is down (below 5 cm, slower than 1 m/s): "
                            "planted feet that do not slide; --features positions only "
                            "(paper: 0)")
        p.add_argument("--foot-step", choices=("expected", "input"), default=d.foot_step,
                       help="the toe step --foot-contact measures: between consecutive "
                            "expected frames, or from the frame fed to the decoder to the "
                            "expected frame it gives (the step generation takes)")
        p.add_argument("--foot-down", choices=("reference", "own"), default=d.foot_down,
                       help="whose toe says a foot is down for --foot-contact: the "
                            "reference's, or the expected frames' own (for a model fed its "
                            "own frames, whose steps fall at other times than the "
                            "reference's)")
        p.add_argument("--plan-parts", type=nonneg_int, default=d.plan_parts, metavar="K",
                       help="feed every decoder step a coarse plan of the motion (per part of "
                            "K of its duration: mean features and mean change), the true one "
                            "in training, one predicted from the sentence when generating; "
                            "needs --progress-input (0: off, the paper's)")
        p.add_argument("--plan-weight", type=nonneg_float, default=d.plan_weight, metavar="W",
                       help="weight of the plan head's mean squared error")
        p.add_argument("--plan-means", choices=("all", "root"), default="all",
                       help="which features' part means the plan holds: all, or only the "
                            "root's ground velocity and heading change (every feature's "
                            "change is in it either way)")
        p.add_argument("--plan-noise", type=nonneg_float, default=d.plan_noise, metavar="STD",
                       help="std of Gaussian noise on the true plan fed while training")
    p.set_defaults(func=cmd_train, model_kind=name)


ROOT_MOTION = ("root_vx", "root_vz", "root_dyaw")


def root_loss_weights(features, weight: float, option: str = "--root-weight") -> list[float]:
    """Per-feature factors: ``weight`` for the root's ground velocity and heading change
    (``ROOT_MOTION``), 1 elsewhere; the model's features (active flag excluded). NLL weights
    (``--root-weight``) and, with weight 0, the input mask of ``--hide-root-input``."""
    from motionlang.features.frames import model_dim
    names = list(features.names)[:model_dim(features)]
    missing = [n for n in ROOT_MOTION if n not in names]
    if missing:
        raise MotionlangError(f"{option} needs features with {', '.join(ROOT_MOTION)} "
                              f"(angles with the root trajectory, or positions); these have no "
                              f"{', '.join(missing)}")
    return [weight if n in ROOT_MOTION else 1.0 for n in names]


def data_source(text: str):
    """argparse type of ``--data``: ``DIR`` or ``DIR@WEIGHT`` (``mixing.parse_source``)."""
    from motionlang.datasets.mixing import parse_source
    try:
        return parse_source(text)
    except MotionlangError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def check_mixed_features(sources, features: str) -> None:
    """Several datasets meet only on the 21-joint body: angle features are MMM's alone."""
    if len(sources) > 1 and features == "angles":
        raise MotionlangError("--features angles are KIT MMM joint angles, which mixed "
                              "datasets do not share: use --features positions with several "
                              "--data")


def mix_training(sources, train_items: list[dict], source_of: dict[str, int], seed: int
                 ) -> list[dict]:
    """Several ``--data``: the training items weighted by their ``@W`` (``mixing.mix_items``;
    unchanged without weights), with a line per dataset of its share of an epoch."""
    from motionlang.datasets.mixing import mix_items, source_counts, source_weights
    if len(sources) < 2:
        return train_items
    n, weights = len(sources), source_weights(sources)
    before = source_counts(train_items, source_of, n)
    if weights:
        train_items = mix_items(train_items, source_of, weights, seed=seed)
    after = source_counts(train_items, source_of, n)
    for s, b, a in zip(sources, before, after):
        print(f"{s}: {a} training pairs per epoch ({a / len(train_items):.0%}; "
              f"{b} before weighting)")
    return train_items


def _new_model(args: argparse.Namespace, data):
    """A fresh M2L or L2M for ``data`` (``datasets.seq2seq_pairs.build_pairs``) as the
    options say, seeded by ``--seed``; an L2M with ``--progress-input`` gets its length
    model fitted on the training pairs."""
    import torch

    from motionlang.datasets.seq2seq_pairs import sentence_lengths
    from motionlang.features.frames import model_dim
    loss_weights = None
    if args.model_kind == "l2m" and args.root_weight != 1.0:   # before anything is written
        loss_weights = root_loss_weights(data.features, args.root_weight)
    input_mask = None
    if args.model_kind == "l2m" and args.hide_root_input:
        input_mask = root_loss_weights(data.features, 0.0, "--hide-root-input")
    plan_mean_mask = None
    if args.model_kind == "l2m" and args.plan_parts and args.plan_means == "root":
        plan_mean_mask = [1.0 - w for w in root_loss_weights(data.features, 0.0,
                                                              "--plan-means root")]
    sizes = dict(enc_hidden=args.enc_hidden, enc_layers=args.enc_layers,
                 dec_hidden=args.dec_hidden, dec_layers=args.dec_layers,
                 embed_dim=args.embed_dim, dropout=args.dropout, attention=args.attention)
    torch.manual_seed(args.seed)
    F, V = model_dim(data.features), len(data.vocab)
    if args.model_kind == "m2l":
        from motionlang.models.seq2seq.m2l import M2LConfig, MotionToLanguage
        model = MotionToLanguage(M2LConfig(n_features=F, vocab_size=V, **sizes),
                                 data.vocab, features=data.features)
    else:
        from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
        longest = max(len(it["motion"]) for it in data.items["train"])
        model = LanguageToMotion(L2MConfig(vocab_size=V, n_features=F,
                                           n_components=args.components, loss=args.loss,
                                           end_weight=args.end_weight,
                                           input_noise=args.input_noise,
                                           time_input=args.time_input,
                                           progress_input=args.progress_input,
                                           rollout=args.rollout,
                                           rollout_warmup=args.rollout_warmup,
                                           rollout_input=args.rollout_input,
                                           loss_weights=loss_weights,
                                           input_mask=input_mask,
                                           energy_weight=args.energy,
                                           foot_weight=args.foot_contact,
                                           mean_weight=args.mean_frames,
                                           foot_step=args.foot_step,
                                           foot_down=args.foot_down,
                                           plan_parts=args.plan_parts,
                                           plan_weight=args.plan_weight,
                                           plan_noise=args.plan_noise,
                                           plan_mean_mask=plan_mean_mask,
                                           max_frames=int(1.5 * longest), **sizes),
                                 data.vocab, features=data.features)
        if args.progress_input:   # it plans its length from the sentence
            from motionlang.models.length import SentenceLength
            model.length_model = SentenceLength.fit(*sentence_lengths(data, "train"))
    return model


def cmd_train(args: argparse.Namespace) -> int:
    import logging

    from motionlang.datasets.mixing import source_weights
    from motionlang.datasets.seq2seq_pairs import balance_repeats, build_pairs, oversample
    from motionlang.datasets.splits import save_splits
    from motionlang.features.frames import model_dim
    from motionlang.training.collate import collate_pairs
    from motionlang.training.run_files import check_resume
    from motionlang.training.trainer import Trainer

    out = Path(args.out)
    check_mixed_features(args.data, args.features)
    source_weights(args.data)   # all weighted or none: checked before the data preparation
    if args.resume:   # before the (long) data preparation and before anything is written
        check_resume(out)
    cfg = train_config(args, out)   # checks the trainer's options before the data preparation
    if args.model_kind == "l2m":
        # numbers are checked by their argparse types (cli/options.py)
        if args.plan_parts and not args.progress_input:
            raise MotionlangError("--plan-parts needs --progress-input")
        if args.foot_step != "expected" and not args.foot_contact > 0:
            raise MotionlangError("--foot-step says which step --foot-contact measures: give "
                                  "--foot-contact W > 0 with it")
        if args.foot_down != "reference" and not args.foot_contact > 0:
            raise MotionlangError("--foot-down says whose foot --foot-contact reads: give "
                                  "--foot-contact W > 0 with it")
        if args.foot_down == "own" and args.foot_step == "input":
            raise MotionlangError("--foot-down own measures consecutive expected frames: it "
                                  "cannot be used with --foot-step input")
    # one line per epoch from the trainer (the progress bar only shows on a terminal)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    data = build_pairs([s.path for s in args.data], features=args.features,
                       offsets=args.offsets, seed=args.seed,
                       min_count=args.min_count, max_seconds=args.max_seconds,
                       mirror=args.mirror, joint_map=args.joint_map)
    if any(str(s.path).startswith("bandai:") for s in args.data) and lead_process():
        from motionlang.cli.run_log import write_license  # CC BY-NC 4.0 data
        write_license(out, args.model_kind.upper())
    train_items = data.items["train"]
    if args.balance > 1:   # before anything is written
        repeats = balance_repeats(data.labels, data.splits["train"], args.balance)
        train_items = oversample(train_items, repeats)
        print(f"balanced: {len(data.items['train'])} -> {len(train_items)} training pairs "
              f"(motions repeated up to {args.balance} times)")
    train_items = mix_training(args.data, train_items, data.sources, args.seed)
    model = _new_model(args, data)   # checks the root options before anything is written
    save_splits(data.splits, out / "splits")
    log_command(out / "commands.jsonl", args)
    print(f"{args.model_kind}: {len(train_items)} training pairs "
          f"({len(data.splits['train'])} motions), vocabulary {len(data.vocab)}, "
          f"{model_dim(data.features)} features/frame, "
          f"{sum(p.numel() for p in model.parameters()):,} parameters")
    trainer = Trainer(model, train_items, collate_pairs, cfg,
                      val_set=data.items.get("val") or None)
    history = trainer.fit(resume=args.resume)
    if trainer.rank == 0:
        best = out / "best.pt"
        # without validation "best" is the lowest training loss, which scheduled sampling
        # raises as it ramps up: then the final weights are the model
        by_train_loss = not data.items.get("val") and getattr(model.config, "rollout", 0) > 0
        final = type(model).load(best) if best.exists() and not by_train_loss else model
        final.save(out / MODEL_FILES[args.model_kind])
        last = history[-1] if history else {}
        print(f"{out / MODEL_FILES[args.model_kind]}: epoch {last.get('epoch')}, train {last.get('train')}, "
              f"val {last.get('val')}")
    return 0


def register_train(train_sub) -> None:
    """Hook of ``cli/train_commands.py``: adds ``train m2l`` and ``train l2m``."""
    _add_train(train_sub, "m2l", "train the motion-to-language model (Plappert et al. 2018)")
    _add_train(train_sub, "l2m", "train the language-to-motion model (Plappert et al. 2018)")

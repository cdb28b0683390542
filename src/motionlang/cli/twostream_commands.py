"""``motionlang train twostream`` and ``motionlang evaluate-t2m``.

Thin wrappers over :mod:`motionlang.datasets.twostream_items` (dataset -> items),
:mod:`motionlang.training.twostream_train` (shared trainer + annealed teacher forcing,
ablations) and :mod:`motionlang.evaluation.t2m.compare` (one table for every
text-to-motion model). torch is imported inside the commands only, so building the CLI
parser stays cheap.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from motionlang.cli.options import (
    frames_int,
    layers_int,
    nonneg_int,
    output_dir,
    positive_float,
    seed_int,
    size_int,
)
from motionlang.cli.train_commands import add_out_arg, add_trainer_args, model_file, train_config
from motionlang.errors import MotionlangError
from motionlang.training.run_log import lead_process, log_command

ABLATION_NAMES = ("full", "no-joint-training", "one-stream", "no-extra-losses", "word-vectors")


def cmd_train(args: argparse.Namespace) -> int:
    import logging

    import torch

    from motionlang.datasets.mixing import source_weights
    from motionlang.datasets.sources import non_commercial
    from motionlang.datasets.splits import save_splits
    from motionlang.datasets.twostream_items import build_twostream_data
    from motionlang.models.length import SentenceLength
    from motionlang.models.twostream import TwoStreamModel
    from motionlang.training.recipes.seq2seq import mix_training
    from motionlang.training.run_files import check_resume
    from motionlang.training.run_log import write_license
    from motionlang.training.twostream_train import ForcingSchedule, make_config, train_twostream

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    run = Path(args.out)
    if args.resume:   # before anything is written: the run's first (or only) stage's
        check_resume(run if (run / "last.pt").is_file() else run / "pose")
    lambdas = parse_lambdas(args.weight)
    cfg = train_config(args, run, length_buckets=args.length_buckets)   # checked at once
    lead = lead_process()  # under torchrun only rank 0 writes files and prints
    source_weights(args.data)   # all weighted or none: checked before the data preparation
    paths = [s.path for s in args.data]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=args.seed,
                                max_seconds=args.max_seconds, max_frames=args.max_frames,
                                mirror=args.mirror)
    train_items = mix_training(args.data, data.items["train"], data.sources, args.seed)
    if lead:
        save_splits(data.splits, run / "splits")
        if non_commercial(args.data):
            write_license(run, "two-stream model")   # CC BY-NC 4.0 data
    log_command(run / "commands.jsonl", args)
    sizes = dict(h1=args.h1, h2=args.h2, h=args.h, lstm_layers=args.lstm_layers)
    fields = dict({k: v for k, v in sizes.items() if v is not None},   # else the config's
                  z_every_step=args.z_every_step, time_input=args.time_input,
                  progress_input=args.progress_input, lambdas=lambdas)
    if args.text_layers:
        fields["text_layers"] = [int(x) for x in args.text_layers.split(",")]
    torch.manual_seed(args.seed)
    model = TwoStreamModel(make_config(args.ablation, **fields), data.features.normalizer)
    model.length_model = SentenceLength.from_items(data.items["train"])
    if lead:
        print(f"twostream ({args.ablation}): {len(data.items['train'])} training pairs "
              f"({len(data.splits['train'])} motions), "
              f"{sum(p.numel() for p in model.parameters()):,} parameters")
    model, history = train_twostream(
        model, train_items, cfg, val_items=data.items.get("val") or None,
        first_frames=data.first_frames(), resume=args.resume,
        schedule=ForcingSchedule(1.0, 0.0, args.forcing_steps))
    if not lead:
        return 0
    out = run / model_file("twostream")
    model.save(out)
    print(run_summary(out, history))
    return 0


def run_summary(out, history: list[dict]) -> str:
    """One line for a finished run: the model file, its last epoch and losses."""
    last = history[-1] if history else {}
    return (f"{out}: epoch {last.get('epoch')}, train loss "
            f"{last.get('train', {}).get('loss', float('nan')):.4g}, "
            f"val loss {last.get('val', {}).get('loss', float('nan')):.4g}")


def parse_lambdas(specs: list[str] | None) -> dict[str, float]:
    """``["adversarial=0.1", ...]`` -> {term: weight}; unknown or repeated terms and weights
    that are not finite and >= 0 are errors naming the option."""
    import math

    from motionlang.models.twostream.config import DEFAULT_LAMBDAS
    out = {}
    for spec in specs or []:
        name, sep, value = spec.partition("=")
        if name in out:
            raise MotionlangError(f"--weight {spec!r}: {name} is given twice")
        if not sep or name not in DEFAULT_LAMBDAS:
            raise MotionlangError(f"--weight {spec!r}: expected TERM=W with TERM one of "
                                  f"{', '.join(DEFAULT_LAMBDAS)}")
        try:
            w = float(value)
        except ValueError:
            w = math.nan
        if not (math.isfinite(w) and w >= 0):
            raise MotionlangError(f"--weight {spec!r}: W must be a finite number >= 0")
        out[name] = w
    return out


def register_train(train_sub) -> None:
    """Hook of ``cli/train_commands.py``: adds ``train twostream``."""
    h = "train the two-stream text-to-motion model (Ghosh et al. 2021)"
    p = train_sub.add_parser("twostream", help=h, description=h)
    from motionlang.cli.train_commands import add_data_arg
    add_data_arg(p)
    add_out_arg(p, "twostream", "best.pt and last.pt (checkpoints; in pose/ and text/ for "
                                "the two-stage ablation), history.json, splits/, ")
    p.add_argument("--ablation", choices=ABLATION_NAMES, default="full",
                   help="the full model or one of the paper's ablations")
    # defaults None: TwoStreamConfig's (the paper's sizes). models.twostream imports torch on
    # import, which building the parser must not
    p.add_argument("--h", type=size_int, default=None,
                   help="stream embedding size (default: the config's, the paper's 512)")
    p.add_argument("--h1", type=size_int, default=None,
                   help="per-part layer size (default: the config's, the paper's 32)")
    p.add_argument("--h2", type=size_int, default=None,
                   help="trunk+limb layer size (default: the config's, the paper's 128)")
    p.add_argument("--lstm-layers", type=layers_int, default=None,
                   help="layers of the sentence LSTM (default: the config's, the paper's 2)")
    p.add_argument("--z-every-step", action="store_true",
                   help="beyond the paper: every decoder step reads its stream's embedding")
    p.add_argument("--time-input", action="store_true",
                   help="beyond the paper: every decoder step reads the elapsed time")
    p.add_argument("--progress-input", action="store_true",
                   help="beyond the paper: every decoder step reads how far through the "
                        "motion it is, (t - 1) / (T - 1) for the frame it reads")
    p.add_argument("--weight", action="append", metavar="TERM=W",
                   help="a loss term's weight, repeatable (terms: pose, manifold, velocity, "
                        "embedding, adversarial, discriminator, energy, foot); terms not given keep "
                        "the paper's weights (energy, foot: 0, beyond the paper; foot: the decoded "
                        "toes' speed in m/s where the reference's toe is down)")
    p.add_argument("--text-layers", metavar="I,J,..",
                   help="hidden states of the text model to concatenate (default: the "
                        "config's, 3,4,5,6)")
    add_trainer_args(p, epochs=20, batch_size=32, grad_clip=5.0)
    p.add_argument("--forcing-steps", type=nonneg_int, default=200,
                   help="optimiser steps over which teacher forcing anneals 1 -> 0")
    p.add_argument("--max-frames", type=frames_int, default=None,
                   help="crop sequences to this many 12.5 Hz frames")
    p.add_argument("--max-seconds", type=positive_float, default=30.0, help="drop longer motions")
    p.add_argument("--length-buckets", type=nonneg_int, default=0, metavar="N",
                   help="batch motions of similar lengths (pools of N batches sorted by "
                        "length; 0: plain shuffle): less padding, faster epochs")
    p.add_argument("--mirror", action="store_true",
                   help="also train on every training motion mirrored left/right, its "
                        "sentences' sides swapped (beyond the paper)")
    p.set_defaults(func=cmd_train)


def cmd_evaluate(args: argparse.Namespace) -> int:
    from motionlang.cli.evaluator_commands import check_protocol, cmd_evaluate_guo
    if args.protocol == "guo":
        return cmd_evaluate_guo(args)
    check_protocol(args)
    from motionlang.cli.models_arg import load_t2m_models
    from motionlang.datasets.twostream_items import build_twostream_data
    from motionlang.evaluation.t2m.compare import compare

    models = load_t2m_models(args.model)
    if args.autoencode and not any(m.autoencodes for m in models.values()):
        raise MotionlangError("--autoencode needs a two-stream model among --model")
    data = build_twostream_data(args.data, seed=args.seed, max_seconds=args.max_seconds)
    _, table = compare(models, data, split=args.split, limit=args.limit or None,
                       autoencode=args.autoencode, out_dir=args.output, figures=args.figures,
                       oracle=args.oracle, true_start=args.true_start)
    print(table, end="")
    return 0


def register(subparsers) -> None:
    from motionlang.cli.evaluator_commands import add_guo_args
    from motionlang.cli.models_arg import add_model_arg
    p = subparsers.add_parser(
        "evaluate-t2m", help="one table for text-to-motion models: APE/AVE and action order "
                             "(--protocol ape) or the papers' R-precision, FID, MM-Dist, "
                             "Diversity (--protocol guo)")
    p.add_argument("--protocol", choices=("ape", "guo"), default="ape",
                   help="ape: positions, velocities and action order against the test "
                        "motions; guo: the yardstick of Guo et al. 2022 under a text-motion "
                        "evaluator (--evaluator)")
    p.add_argument("--data", required=True, metavar="DIR", help="the dataset trained on")
    add_model_arg(p, help="a text-to-motion model (file, run folder or packaged name) with "
                          "its sampling options, one row each; repeat for each model (ape: at "
                          "least one; guo: default the packaged l2m), e.g. --model l2m "
                          "--model l2m:method=sample,width=10,rerank=m2l")
    p.add_argument("--split", default="test", help="the split to evaluate (in the dataset's "
                   "splits, as training made them with --seed)")
    p.add_argument("--seed", type=seed_int, default=0, help="the split seed used in training")
    p.add_argument("--max-seconds", type=positive_float, default=30.0,
                   help="drop longer motions (as in training)")
    p.add_argument("--limit", type=nonneg_int, default=0, help="evaluate at most N motions")
    p.add_argument("--autoencode", action="store_true",
                   help="also score each two-stream model decoding the test motions from their "
                        "own pose embeddings and first poses (a reference for the sentence path)")
    p.add_argument("--true-start", action="store_true",
                   help="also score each two-stream model generating from the sentence but "
                        "starting at the test motion's first pose (as JL2P and Ghosh et al. "
                        "evaluate), each L2M model (joint angles) on the test subject's own "
                        "body, and on it starting with the test motion's first frame, and "
                        "standing in the first pose")
    p.add_argument("--figures", type=nonneg_int, default=3, help="trajectory figures to draw")
    p.add_argument("--oracle", type=nonneg_int, default=0, metavar="K",
                   help="procedural corpus: a second table on the test motions whose exact "
                        "parameters K or more training motions share, with the APE of those "
                        "motions (how much of APE no sentence can explain)")
    p.add_argument("-o", "--output", metavar="DIR", type=output_dir,
                   help="write t2m_table.md, t2m_report.json and trajectory PNGs here")
    add_guo_args(p)
    p.set_defaults(func=cmd_evaluate)

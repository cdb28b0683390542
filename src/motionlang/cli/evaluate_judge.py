"""``motionlang evaluate-judge``: text-to-motion models judged on real motion.

Parsing and printing over :func:`motionlang.evaluation.judge_bandai.evaluate_on_bandai`;
``--model`` values go through :mod:`motionlang.cli.models_arg`. ``train judge`` is generated
from its recipe (``recipes.judge``) by ``cli/train.py``. The judge is
trained on the Bandai Namco datasets, CC BY-NC 4.0: it and every figure made with it are for
non-commercial use only. torch is imported inside the command only.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.cli.models_arg import add_model_arg, load_t2m_models
from motionlang.cli.options import nonneg_int, output_dir, seed_int
from motionlang.evaluation.judge_bandai import FOOT_LOCK, evaluate_on_bandai
from motionlang.models.registry import load_model
from motionlang.recipes.judge import NON_COMMERCIAL
from motionlang.utils.atomic import write_texts


def cmd_evaluate(args: argparse.Namespace) -> int:

    judge = load_model(args.judge, kind="judge")
    models = load_t2m_models(args.model)
    got = evaluate_on_bandai(judge, models, args.data, args.split, limit=args.limit,
                             seed=args.seed, foot_lock=args.foot_lock,
                             judge_name=str(args.judge))
    text = got.markdown()
    print(text, end="")
    if args.output:
        report = {**got.report, "models": dict(zip(models, args.model or []))}
        write_texts({Path(args.output) / "judge_table.md": text, Path(args.output) /
                     "judge_report.json": json.dumps(report, indent=1) + "\n"})
    return 0


def register(subparsers) -> None:
    h = "judge text-to-motion models on real motion (Bandai Namco test takes)"
    p = subparsers.add_parser(
        "evaluate-judge", help=h, description=h + ": the judge's own accuracy on the real "
        "takes; each model's motions for one sentence per take, recognised as the asked "
        "content and style, FID and diversity on the judge's features, foot skating, floor "
        f"penetration, largest one-frame root jump, beside the real takes. {NON_COMMERCIAL}")
    p.add_argument("--judge", required=True, metavar="J",
                   help="a judge file or run folder (train judge --out)")
    p.add_argument("--data", required=True, metavar="bandai:DIR",
                   help="the Bandai Namco datasets (CC BY-NC 4.0)")
    add_model_arg(p, help="a text-to-motion model (file, run folder or packaged name, e.g. "
                          "l2m) with its sampling options; repeat for each model (none: the "
                          "judge and the real takes only)")
    p.add_argument("--split", choices=("train", "val", "test"), default="test",
                   help="the Bandai split judged")
    p.add_argument("--limit", type=nonneg_int, default=0,
                   help="judge N takes (0: all): a sample drawn with --seed, stratified by "
                        "the asked action")
    p.add_argument("--seed", type=seed_int, default=0,
                   help="seed of the sentences, the sampling models' draws and the FID halves")
    p.add_argument("--foot-lock", choices=FOOT_LOCK, default="on",
                   help="judge the motions with feet that are down held in place, as "
                        "'motionlang generate' writes joint-position models' motions (on), "
                        "as decoded (off), or both (rows NAME and 'NAME (raw)')")
    p.add_argument("-o", "--output", metavar="DIR", type=output_dir,
                   help="write judge_table.md and judge_report.json here")
    p.set_defaults(func=cmd_evaluate)

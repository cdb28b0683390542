"""``motionlang evaluate-t2m``: one table for text-to-motion models.

Parsing and printing only: ``--protocol ape`` is
:func:`motionlang.evaluation.t2m.ape.evaluate_ape`, ``--protocol guo`` is
``cli/evaluate_guo.py``'s; the ``--model`` values are loaded by
:mod:`motionlang.cli.models_arg`. (``train twostream`` is generated from its recipe,
``recipes/twostream.py``.) torch is imported inside the commands only, so building
the CLI parser stays cheap.
"""
from __future__ import annotations

import argparse

from motionlang.cli.evaluate_guo import add_guo_args, check_protocol, cmd_evaluate_guo
from motionlang.cli.models_arg import add_model_arg, load_t2m_models
from motionlang.cli.options import nonneg_int, output_dir, positive_float, seed_int
from motionlang.evaluation.t2m.ape import evaluate_ape


def cmd_evaluate(args: argparse.Namespace) -> int:
    if args.protocol == "guo":
        return cmd_evaluate_guo(args)
    check_protocol(args)
    _, table = evaluate_ape(load_t2m_models(args.model), args.data, split=args.split,
                            seed=args.seed, max_seconds=args.max_seconds, limit=args.limit,
                            autoencode=args.autoencode, true_start=args.true_start,
                            oracle=args.oracle, out_dir=args.output, figures=args.figures)
    print(table, end="")
    return 0


def register(subparsers) -> None:
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
    p.add_argument("--limit", type=nonneg_int, default=0,
                   help="evaluate N motions (0: all): a sample drawn with --seed, stratified "
                        "by the first ground-truth action where the data has one")
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

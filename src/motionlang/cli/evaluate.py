"""``motionlang evaluate``: BLEU / ROUGE / CIDEr of an M2L model against the nearest-neighbour
baseline, and optionally a text-to-motion model's round trip (sentence -> motion -> M2L
description; ``--t2m MODEL[:options]``, ``cli.models_arg``).

A thin layer over :func:`motionlang.evaluation.seq2seq_report.evaluate_seq2seq`; ``--m2l`` is
a model file or its run folder (``train m2l --out DIR``), whose ``splits/`` says which
motions are the test set.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.cli.config_options import add_config_options
from motionlang.cli.models_arg import add_model_arg, load_t2m
from motionlang.cli.options import nonneg_int, output_file, positive_float
from motionlang.datasets.seq2seq_pairs import load_sources
from motionlang.datasets.sources import parse_source
from motionlang.datasets.splits import load_splits
from motionlang.errors import MotionlangError
from motionlang.library.options import DescribeOptions
from motionlang.models.registry import resolve  # a run folder -> its model file
from motionlang.utils.atomic import atomic_write


def _evaluate_models(args: argparse.Namespace):
    """(M2L file, round-trip model or None): the round trip's model (with its options and
    reranker) loaded first, as its errors come before the long M2L run."""
    from motionlang.evaluation.seq2seq import round_trip_model
    m2l_path = resolve(args.m2l)
    if not args.t2m:
        return m2l_path, None
    _, t2m = load_t2m(args.t2m, "--t2m")
    round_trip_model(t2m, f"--t2m {args.t2m}")
    rerank = getattr(t2m.options, "rerank", None)
    if rerank and resolve(rerank).resolve() == m2l_path.resolve():
        raise MotionlangError(f"--t2m {args.t2m}: the reranker must not be the describer "
                              "(--m2l), which would grade its own choice")
    return m2l_path, t2m


def cmd_evaluate(args: argparse.Namespace) -> int:
    from motionlang.evaluation.seq2seq_report import evaluate_seq2seq, report_text
    from motionlang.models.seq2seq.m2l import MotionToLanguage

    m2l_path, t2m = _evaluate_models(args)
    m2l = MotionToLanguage.load(m2l_path)
    splits = load_splits(args.splits or m2l_path.parent / "splits")
    weighted = [d for d in args.data if parse_source(d).weight is not None]
    if weighted:
        raise MotionlangError(f"--data {weighted[0]}: weights (@W) are for training; "
                              f"evaluate reads each motion once")
    records = {r.id: r for r in load_sources(args.data, args.max_seconds)[0]}
    report = evaluate_seq2seq(m2l, records, splits, split=args.split, width=args.width,
                              limit=args.limit, length_penalty=args.length_penalty,
                              rank=args.rank, t2m=t2m, t2m_name=args.t2m, tsne=args.tsne)
    text = report_text(report)
    if args.output:
        out = Path(args.output)
        with atomic_write(out) as fh:
            json.dump(report, fh, indent=1)
        with atomic_write(out.with_suffix(".md")) as fh:
            fh.write(text)
    print(text, end="")
    return 0


def register(subparsers) -> None:
    from dataclasses import fields

    p = subparsers.add_parser("evaluate", help="BLEU/ROUGE/CIDEr of M2L, baseline, L2M round trip")
    p.add_argument("--m2l", required=True, metavar="MODEL",
                   help="M2L model file or its run folder (train m2l --out), which holds "
                        "splits/")
    add_model_arg(p, "--t2m", repeat=False,
                  help="a text-to-motion model (file, run folder or packaged name) with its "
                       "sampling options: also run the round trip (each test sentence -> its "
                       "motion -> the M2L's description; the model's own frames, so one of the "
                       "M2L's features: an L2M), and its baseline (the motion of the closest "
                       "training sentence in bag of words); e.g. --t2m l2m:method=sample,"
                       "width=10,rerank=OTHER_M2L (a reranker other than --m2l)")
    p.add_argument("--data", required=True, action="append", metavar="DIR",
                   help="the dataset trained on (KIT-ML-format or custom folder, bandai:DIR, "
                        "...); repeat it for several (no @W weights here). The test motions "
                        "are those of --splits found in these datasets; on Bandai takes also "
                        "the share of top descriptions naming the take's action and style, "
                        "beside the nearest neighbour's")
    p.add_argument("--splits", metavar="DIR", help="split files (default: M2L_DIR/splits)")
    p.add_argument("--split", default="test", help="the split to evaluate (of --splits)")
    p.add_argument("--limit", type=nonneg_int, default=0,
                   help="evaluate N motions of the split (0: all): a random sample (seed 0)")
    p.add_argument("--max-seconds", type=positive_float, default=30.0,
                   help="drop longer motions (as in training)")
    p.add_argument("-o", "--output", type=output_file, help="report.json (+ report.md beside it)")
    p.add_argument("--tsne", metavar="PNG", type=output_file,
                   help="also plot the context vectors' t-SNE map")
    # the beam options of describe; rank logp is the paper's protocol, mbr scores what
    # describe shows
    add_config_options(p, DescribeOptions, defaults={"rank": "logp"},
                       skip=tuple(f.name for f in fields(DescribeOptions)
                                  if f.name not in ("width", "length_penalty", "rank")))
    p.set_defaults(func=cmd_evaluate)

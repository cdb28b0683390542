"""``motionlang evaluate``: BLEU / ROUGE / CIDEr of an M2L model against the nearest-neighbour
baseline, and optionally a text-to-motion model's round trip (sentence -> motion -> M2L
description; ``--t2m MODEL[:options]``, ``cli.models_arg``).

A thin wrapper over :mod:`motionlang.evaluation.seq2seq`; ``--m2l`` is a model file or its
run folder (``train m2l --out DIR``), whose ``splits/`` says which motions are the test set.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from motionlang.cli.options import nonneg_float, nonneg_int, output_file, positive_float, width_int
from motionlang.cli.text_commands import add_rank_arg, check_length_penalty
from motionlang.errors import MotionlangError


def _evaluate_models(args: argparse.Namespace):
    """The options about models checked, and (M2L file, round-trip model or None) loaded:
    the round trip's model (with its options and reranker) first, as its errors come
    before the long M2L run."""
    from motionlang.cli.models_arg import load_t2m
    from motionlang.evaluation.seq2seq import round_trip_model
    from motionlang.models.registry import resolve  # a run folder -> its model file
    check_length_penalty(args.length_penalty)
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


def _report_text(report: dict, args: argparse.Namespace) -> str:
    """The printed (and report.md) form of ``evaluate``'s report: the score table, BLEU
    by rank, parameters and labels named where the data has them."""
    from motionlang.evaluation import seq2seq as ev
    table = ev.markdown_table({"M2L (top hypothesis)": report["m2l"],
                               "nearest neighbour": report["nearest_neighbour"],
                               **({f"L2M round trip ({_decoding(report['l2m_round_trip'])})":
                                   report["l2m_round_trip"],
                                   "nearest training sentence, round trip":
                                   report["nn_round_trip"]}
                                  if "l2m_round_trip" in report else {})})
    by_rank = " ".join(f"{b:.3f}" for b in report["m2l"]["bleu_by_rank"])
    table += (f"\nM2L BLEU of hypotheses 1..{args.width} (ordered by --rank {args.rank}): "
              f"{by_rank}\n")
    if "m2l_actions_by_rank" in report:
        table += (f"M2L hypotheses 1..{args.width} naming exactly the true actions: " +
                  " ".join(f"{a:.1%}" for a in report["m2l_actions_by_rank"]) + "\n")
    for key, name in (("m2l_parameters", "M2L top description"),
                      ("l2m_parameters", "L2M round trip"),
                      ("nn_parameters", "Nearest training sentence, round trip")):
        if key in report:
            acc = report[key]
            table += (f"{name}, parameters right (procedural ground truth): " + ", ".join(
                f"{f} {acc[f]:.1%} of {acc[f + '_stated']}" for f in
                ("side", "count", "direction", "speed")) +
                f"; actions exactly right {acc['actions_match']:.1%}\n")
            if "named" in acc:
                table += f"{name}, true actions named: " + ev.named_line(acc["named"]) + "\n"
    for key, name in (("m2l_labels", "M2L top description"),
                      ("nn_labels", "Nearest neighbour")):
        if key in report:
            acc = report[key]
            table += (f"{name}, labelled takes ({acc['n']}): action named {acc['content']:.1%}, "
                      f"style named {acc['style']:.1%}, both {acc['both']:.1%}\n")
    return table


def _decoding(trip: dict) -> str:
    """How the round trip's motions were made, for its row: "mean", "sample", "sample, best
    of 5 by reranker"."""
    text = str(trip.get("method") or "mean")
    if trip.get("rerank"):
        text += f", best of {trip.get('width')} by reranker"
    return text


def _add_checks(report: dict, records: dict, test: dict, train: dict, refs: dict,
                width: int) -> None:
    """Beyond BLEU, into ``report``: on labelled takes (Bandai) whether the action and
    style are named (M2L and nearest neighbour); on a procedural corpus the parameters
    each description states, checked against the generator's ground truth."""
    from motionlang.evaluation import seq2seq as ev
    labelled = _labels(records, test)
    if labelled:   # Bandai takes: is the action named, and the style?
        top = {e["id"]: e["hypotheses"][0] for e in report["m2l"]["all"] if e["id"] in labelled}
        nn = ev.nearest_neighbour_descriptions(train, refs, {i: test[i] for i in labelled})
        report["m2l_labels"] = ev.label_accuracy(top, labelled)
        report["nn_labels"] = ev.label_accuracy(nn, labelled)
    truths = _ground_truths(records, test)
    if truths:   # a procedural corpus: the parameters each description states, checked
        ranked = {e["id"]: e["hypotheses"] for e in report["m2l"].pop("all")}
        report["m2l_parameters"] = ev.parameter_accuracy(
            {i: h[0] for i, h in ranked.items()}, truths)
        # BLEU cannot tell a worse description from an equally valid paraphrase; the
        # parameters can: how often the k-th hypothesis names exactly the true actions
        # (evaluate_m2l pads a short beam with its last hypothesis, so all have W)
        report["m2l_actions_by_rank"] = [
            ev.parameter_accuracy({i: h[k] for i, h in ranked.items()}, truths)["actions_match"]
            for k in range(width)]
        for run in ("l2m", "nn"):
            if f"{run}_round_trip" in report:
                descriptions = report[f"{run}_round_trip"]["descriptions"]
                report[f"{run}_parameters"] = ev.round_trip_parameter_accuracy(
                    descriptions, truths)
                report[f"{run}_parameters"]["named"] = ev.actions_named(descriptions, truths)
    else:
        report["m2l"].pop("all")


def cmd_evaluate(args: argparse.Namespace) -> int:
    from motionlang.datasets.mixing import parse_source
    from motionlang.datasets.seq2seq_pairs import load_sources
    from motionlang.datasets.splits import load_splits
    from motionlang.evaluation import seq2seq as ev
    from motionlang.features.frames import motion_frames
    from motionlang.models.seq2seq.m2l import MotionToLanguage
    from motionlang.utils.atomic import atomic_write
    from motionlang.utils.progress import progress

    m2l_path, t2m = _evaluate_models(args)
    m2l = MotionToLanguage.load(m2l_path)
    splits = load_splits(args.splits or m2l_path.parent / "splits")
    for name in ("train", args.split):
        if name not in splits:
            raise MotionlangError(f"no {name!r} split (have {sorted(splits)})")
    weighted = [d for d in args.data if parse_source(d).weight is not None]
    if weighted:
        raise MotionlangError(f"--data {weighted[0]}: weights (@W) are for training; "
                              f"evaluate reads each motion once")
    records = {r.id: r for r in load_sources(args.data, args.max_seconds)[0]}

    def frames(ids, limit=None):
        ids = [i for i in ids if i in records][:limit]
        return {i: motion_frames(m2l.features, records[i].load_motion(), 1)[0]
                for i in progress(ids, desc="encode", unit="motion")}
    # --limit caps the evaluated split only: the baseline searches the whole training set
    n_eval = len([i for i in splits[args.split] if i in records][:args.limit or None])
    if args.tsne and n_eval < 4:
        raise MotionlangError(f"--tsne needs at least 4 motions in the {args.split!r} split, "
                              f"it has {n_eval}")
    test, train = frames(splits[args.split], args.limit or None), frames(splits["train"])
    refs = {i: records[i].annotations for i in {**test, **train}}
    report = {"split": args.split, "length_penalty": args.length_penalty, "rank": args.rank,
              "m2l": ev.evaluate_m2l(m2l, test, refs, args.width, args.length_penalty,
                                     rank=args.rank),
              "nearest_neighbour": ev.evaluate_nn_baseline(train, refs, test, refs)}
    if t2m is not None:
        report["l2m_round_trip"] = ev.round_trip_of(t2m, m2l, {i: refs[i] for i in test},
                                                    report["m2l"]["bleu"])
        report["l2m_round_trip"].update(model=args.t2m, **dataclasses.asdict(t2m.options))
        from motionlang.evaluation.retrieval import SentenceIndex
        index = SentenceIndex((i, s) for i in sorted(train) for s in refs[i])
        report["nn_round_trip"] = ev.evaluate_round_trip_nn(
            index, train, m2l, {i: refs[i] for i in test}, report["m2l"]["bleu"])
    _add_checks(report, records, test, train, refs, args.width)
    if args.tsne:
        _context_tsne(Path(args.tsne), m2l, t2m.model if t2m is not None else None, test,
                      records)
        report["tsne"] = str(args.tsne)
    table = _report_text(report, args)
    if args.output:
        out = Path(args.output)
        with atomic_write(out) as fh:
            json.dump(report, fh, indent=1)
        with atomic_write(out.with_suffix(".md")) as fh:
            fh.write(table)
    print(table, end="")
    return 0


def _labels(records: dict, ids) -> dict:
    """{id: {"content", "style"}} of the motions among ``ids`` that carry those labels
    (Bandai takes)."""
    out = {}
    for i in ids:
        lab = getattr(records[i], "labels", None)
        if isinstance(lab, dict) and "content" in lab and "style" in lab:
            out[i] = lab
    return out


def _ground_truths(records: dict, ids) -> dict:
    """{id: ground-truth primitives} when every record carries them (procedural corpus)."""
    from motionlang.datasets.synth import ground_truth
    metas = {i: records[i].meta for i in ids}
    if not metas or not all(m.get("primitives") for m in metas.values()):
        return {}
    return {i: ground_truth(m) for i, m in metas.items()}


def _context_tsne(path: Path, m2l, l2m, test: dict, records: dict) -> None:
    """The paper's Fig. 9: t-SNE of both encoders' context vectors, coloured by motion type
    (the first action of a procedural sample, else the first word after "a person")."""
    from motionlang.evaluation.context_tsne import l2m_contexts, m2l_contexts, plot_context_tsne

    def label(i):
        prims = records[i].meta.get("primitives")
        if prims:
            return prims[0]["action"]
        words = records[i].annotations[0].lower().split()
        return words[2] if len(words) > 2 and words[:2] == ["a", "person"] else words[0]
    ids = sorted(test)
    panels = {"M2L encoder (motions)": (m2l_contexts(m2l, [test[i] for i in ids]),
                                        [label(i) for i in ids])}
    if l2m is not None:
        panels["L2M encoder (sentences)"] = (
            l2m_contexts(l2m, [records[i].annotations[0] for i in ids]), [label(i) for i in ids])
    plot_context_tsne(panels, path)


def register(subparsers) -> None:
    from motionlang.cli.models_arg import add_model_arg
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
    p.add_argument("-w", "--width", type=width_int, default=5,
                   help="M2L beam width: hypotheses per motion")
    p.add_argument("--limit", type=nonneg_int, default=0, help="evaluate at most N motions")
    p.add_argument("--max-seconds", type=positive_float, default=30.0,
                   help="drop longer motions (as in training)")
    p.add_argument("-o", "--output", type=output_file, help="report.json (+ report.md beside it)")
    p.add_argument("--tsne", metavar="PNG", type=output_file,
                   help="also plot the context vectors' t-SNE map")
    p.add_argument("--length-penalty", type=nonneg_float, default=0.0, metavar="ALPHA",
                   help="rank M2L hypotheses by log P / length**ALPHA (default 0: total, the paper's)")
    add_rank_arg(p, "logp")   # the paper's protocol; --rank mbr scores what describe shows
    p.set_defaults(func=cmd_evaluate)


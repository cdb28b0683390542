"""``motionlang train m2l|l2m`` and ``motionlang evaluate`` (``describe`` and ``generate``
live in :mod:`motionlang.cli.text_commands`).

Thin wrappers over :mod:`motionlang.datasets.seq2seq_pairs` (dataset -> pairs),
:class:`motionlang.training.trainer.Trainer` and :mod:`motionlang.decoding.seq2seq`.
``--data`` is a KIT-ML-format folder (the release, or a procedural corpus) or a custom
folder of motion files with ``captions.csv``/``captions.jsonl``.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.cli.options import (
    dropout_float, layers_int, nonneg_float, nonneg_int, output_dir, output_file,
    positive_float, positive_int, probability, seed_int, size_int, width_int)
from motionlang.cli.run_log import log_command
from motionlang.cli.text_commands import check_length_penalty
from motionlang.cli.train_commands import add_schedule_args, schedule_options
from motionlang.errors import MotionlangError

# ------------------------------------------------------------------ train m2l | l2m
def _add_train(sub, name: str, help_: str) -> None:
    # torch-free config module: building the parser must not import torch
    from motionlang.models.seq2seq.config import L2MConfig, M2LConfig
    d = M2LConfig(1, 1) if name == "m2l" else L2MConfig(1, 1)
    p = sub.add_parser(name, help=help_, description=help_)
    p.add_argument("--data", required=True, metavar="DIR", help="KIT-ML-format or custom folder")
    p.add_argument("--out", default=f"runs/{name}", metavar="DIR", type=output_dir,
                   help="run folder: last.pt, best.pt, model.pt, history, splits")
    p.add_argument("--features", choices=("angles", "positions"), default="angles",
                   help="angles: the 44 MMM joint angles (KIT MMM motions only); positions: "
                        "the 21-joint body (any rig that maps onto it)")
    p.add_argument("--joint-map", metavar="MAP.json", default=None,
                   help="how a custom folder's rig maps onto the 21-joint body (default: "
                        "joint_map.json in the folder, else chosen by joint names)")
    p.add_argument("--offsets", type=positive_int, default=10,
                   help="down-sampling start offsets per motion (augmentation, default 10)")
    p.add_argument("--max-seconds", type=positive_float, default=30.0, help="drop longer motions")
    p.add_argument("--min-count", type=positive_int, default=1,
                   help="vocabulary: minimum word count")
    p.add_argument("--epochs", type=positive_int, default=20)
    p.add_argument("--batch-size", type=positive_int, default=128)
    p.add_argument("--lr", type=positive_float, default=1e-3)
    add_schedule_args(p)
    p.add_argument("--grad-clip", type=nonneg_float, default=None if name == "m2l" else 25.0)
    p.add_argument("--seed", type=seed_int, default=0)
    p.add_argument("--resume", action="store_true", help="continue from OUT/last.pt")
    p.add_argument("--checkpoint-every", type=nonneg_int, default=0, metavar="STEPS")
    p.add_argument("--enc-hidden", type=size_int, default=d.enc_hidden)
    p.add_argument("--enc-layers", type=layers_int, default=d.enc_layers)
    p.add_argument("--dec-hidden", type=size_int, default=d.dec_hidden)
    p.add_argument("--dec-layers", type=layers_int, default=d.dec_layers)
    p.add_argument("--embed-dim", type=size_int, default=d.embed_dim)
    p.add_argument("--dropout", type=dropout_float, default=d.dropout)
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
        p.add_argument("--components", type=size_int, default=d.n_components)
        p.add_argument("--loss", choices=("surrogate", "exact"), default=d.loss)
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


def cmd_train(args: argparse.Namespace) -> int:
    import logging

    import torch

    from motionlang.datasets.splits import save_splits
    from motionlang.features.frames import model_dim
    from motionlang.training.collate import collate_pairs
    from motionlang.datasets.seq2seq_pairs import (balance_repeats, build_pairs, oversample,
                                                  sentence_lengths)
    from motionlang.training.trainer import TrainConfig, Trainer, check_resume

    if args.resume:   # before the (long) data preparation and before anything is written
        check_resume(args.out)
    schedule = schedule_options(args)
    if args.model_kind == "l2m":
        # numbers are checked by their argparse types (cli/options.py)
        if args.plan_parts and not args.progress_input:
            raise MotionlangError("--plan-parts needs --progress-input")
    # one line per epoch from the trainer (the progress bar only shows on a terminal)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    data = build_pairs(args.data, features=args.features, offsets=args.offsets, seed=args.seed,
                       min_count=args.min_count, max_seconds=args.max_seconds,
                       mirror=args.mirror, joint_map=args.joint_map)
    train_items = data.items["train"]
    if args.balance > 1:   # before anything is written
        repeats = balance_repeats(data.labels, data.splits["train"], args.balance)
        train_items = oversample(train_items, repeats)
        print(f"balanced: {len(data.items['train'])} -> {len(train_items)} training pairs "
              f"(motions repeated up to {args.balance} times)")
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
    out = Path(args.out)
    save_splits(data.splits, out / "splits")
    log_command(out / "commands.jsonl", args)
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
                                           plan_parts=args.plan_parts,
                                           plan_weight=args.plan_weight,
                                           plan_noise=args.plan_noise,
                                           plan_mean_mask=plan_mean_mask,
                                           max_frames=int(1.5 * longest), **sizes),
                                 data.vocab, features=data.features)
        if args.progress_input:   # it plans its length from the sentence
            from motionlang.models.length import SentenceLength
            model.length_model = SentenceLength.fit(*sentence_lengths(data, "train"))
    cfg = TrainConfig(epochs=args.epochs, batch_size=args.batch_size, lr=args.lr,
                      grad_clip=args.grad_clip, seed=args.seed, out_dir=str(out),
                      checkpoint_every=args.checkpoint_every, **schedule)
    print(f"{args.model_kind}: {len(train_items)} training pairs "
          f"({len(data.splits['train'])} motions), vocabulary {V}, {F} features/frame, "
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
        final.save(out / "model.pt")
        last = history[-1] if history else {}
        print(f"{out / 'model.pt'}: epoch {last.get('epoch')}, train {last.get('train')}, "
              f"val {last.get('val')}")
    return 0


def register_train(train_sub) -> None:
    """Hook of ``cli/train_commands.py``: adds ``train m2l`` and ``train l2m``."""
    _add_train(train_sub, "m2l", "train the motion-to-language model (Plappert et al. 2018)")
    _add_train(train_sub, "l2m", "train the language-to-motion model (Plappert et al. 2018)")


# ------------------------------------------------------------------ describe / generate
def cmd_evaluate(args: argparse.Namespace) -> int:
    from motionlang.datasets.splits import load_splits
    from motionlang.features.frames import motion_frames
    from motionlang.evaluation import seq2seq as ev
    from motionlang.models.seq2seq.m2l import MotionToLanguage
    from motionlang.datasets.seq2seq_pairs import load_records
    from motionlang.utils.atomic import atomic_write
    from motionlang.utils.progress import progress

    check_length_penalty(args.length_penalty)
    if args.l2m_method == "mean" and args.l2m_width != 1:
        raise MotionlangError("--l2m-width applies to 'sample' and 'beam'; mean decoding gives "
                              "one motion")
    if not args.l2m_temperature > 0:
        raise MotionlangError(f"--l2m-temperature must be > 0, got {args.l2m_temperature}")
    if args.l2m_method == "mean" and args.l2m_temperature != 1.0:
        raise MotionlangError("--l2m-temperature applies to 'sample' and 'beam'; mean decoding "
                              "draws nothing")
    m2l_path = Path(args.m2l)
    if args.l2m_rerank:
        if not args.l2m:
            raise MotionlangError("--l2m-rerank ranks the round trip's motions: give --l2m")
        if args.l2m_method == "mean" or args.l2m_width < 2:
            raise MotionlangError("--l2m-rerank needs several motions per sentence: "
                                  "--l2m-method sample or beam with --l2m-width > 1")
        if Path(args.l2m_rerank).resolve() == m2l_path.resolve():
            raise MotionlangError(f"--l2m-rerank {args.l2m_rerank}: the reranker must not be "
                                  "the describer (--m2l), which would grade its own choice")
    l2m = reranker = None
    if args.l2m:
        from motionlang.models.seq2seq.l2m import LanguageToMotion
        l2m = LanguageToMotion.load(args.l2m)
    if args.l2m_rerank:   # before the long M2L evaluation
        from motionlang.decoding.rerank import check_same_features
        reranker = MotionToLanguage.load(args.l2m_rerank)
        check_same_features(l2m, reranker, f"--l2m-rerank {args.l2m_rerank}")
    m2l = MotionToLanguage.load(m2l_path)
    splits = load_splits(args.splits or m2l_path.parent / "splits")
    for name in ("train", args.split):
        if name not in splits:
            raise MotionlangError(f"no {name!r} split (have {sorted(splits)})")
    records = {r.id: r for r in load_records(args.data, args.max_seconds) if r.annotations}

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
    report = {"split": args.split, "length_penalty": args.length_penalty,
              "m2l": ev.evaluate_m2l(m2l, test, refs, args.width, args.length_penalty),
              "nearest_neighbour": ev.evaluate_nn_baseline(train, refs, test, refs)}
    if l2m is not None:
        report["l2m_round_trip"] = ev.evaluate_round_trip(
            l2m, m2l, {i: refs[i] for i in test}, report["m2l"]["bleu"],
            method=args.l2m_method, width=args.l2m_width, temperature=args.l2m_temperature,
            reranker=reranker)
        report["l2m_round_trip"].update(method=args.l2m_method, width=args.l2m_width,
                                        temperature=args.l2m_temperature,
                                        rerank=args.l2m_rerank)
        from motionlang.evaluation.retrieval import SentenceIndex
        index = SentenceIndex((i, s) for i in sorted(train) for s in refs[i])
        report["nn_round_trip"] = ev.evaluate_round_trip_nn(
            index, train, m2l, {i: refs[i] for i in test}, report["m2l"]["bleu"])
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
            for k in range(args.width)]
        for run in ("l2m", "nn"):
            if f"{run}_round_trip" in report:
                descriptions = report[f"{run}_round_trip"]["descriptions"]
                report[f"{run}_parameters"] = ev.round_trip_parameter_accuracy(
                    descriptions, truths)
                report[f"{run}_parameters"]["named"] = ev.actions_named(descriptions, truths)
    else:
        report["m2l"].pop("all")
    if args.tsne:
        _context_tsne(Path(args.tsne), m2l, l2m if args.l2m else None, test, records)
        report["tsne"] = str(args.tsne)
    table = ev.markdown_table({"M2L (top hypothesis)": report["m2l"],
                               "nearest neighbour": report["nearest_neighbour"],
                               **({f"L2M round trip ({args.l2m_method}"
                                   + (f", best of {args.l2m_width} by reranker" if args.l2m_rerank
                                      else "") + ")":
                                   report["l2m_round_trip"],
                                   "nearest training sentence, round trip":
                                   report["nn_round_trip"]}
                                  if "l2m_round_trip" in report else {})})
    by_rank = " ".join(f"{b:.3f}" for b in report["m2l"]["bleu_by_rank"])
    table += f"\nM2L BLEU of hypotheses 1..{args.width}: {by_rank}\n"
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
                table += f"{name}, true actions named: " + named_line(acc["named"]) + "\n"
    if args.output:
        out = Path(args.output)
        with atomic_write(out) as fh:
            json.dump(report, fh, indent=1)
        with atomic_write(out.with_suffix(".md")) as fh:
            fh.write(table)
    print(table, end="")
    return 0


def named_line(named: dict) -> str:
    """``evaluation.seq2seq.actions_named``'s result as one line of text."""
    return ", ".join(f"{place} {named[place]:.1%} of {named['n_' + place]}"
                     for place in ("first", "later", "only"))


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
    p = subparsers.add_parser("evaluate", help="BLEU/ROUGE/CIDEr of M2L, baseline, L2M round trip")
    p.add_argument("--m2l", required=True, help="M2L model file (its run folder holds splits/)")
    p.add_argument("--l2m", help="L2M model file: also run the round trip, and its baseline "
                   "(the motion of the closest training sentence in bag of words)")
    p.add_argument("--data", required=True, metavar="DIR", help="the dataset trained on")
    p.add_argument("--splits", metavar="DIR", help="split files (default: M2L_DIR/splits)")
    p.add_argument("--split", default="test")
    p.add_argument("-w", "--width", type=width_int, default=5)
    p.add_argument("--limit", type=nonneg_int, default=0, help="evaluate at most N motions")
    p.add_argument("--max-seconds", type=positive_float, default=30.0)
    p.add_argument("-o", "--output", type=output_file, help="report.json (+ report.md beside it)")
    p.add_argument("--tsne", metavar="PNG", type=output_file,
                   help="also plot the context vectors' t-SNE map")
    p.add_argument("--length-penalty", type=nonneg_float, default=0.0, metavar="ALPHA",
                   help="rank M2L hypotheses by log P / length**ALPHA (default 0: total, the paper's)")
    p.add_argument("--l2m-method", choices=("mean", "sample", "beam"), default="mean",
                   help="round trip: how each motion is generated (default: heaviest-component "
                        "means); the likeliest of --l2m-width hypotheses is described (with "
                        "--l2m-rerank: the one that M2L ranks first)")
    p.add_argument("--l2m-width", type=width_int, default=1, metavar="W",
                   help="hypotheses per sentence for 'sample' / 'beam' (default 1)")
    p.add_argument("--l2m-temperature", type=positive_float, default=1.0, metavar="TAU",
                   help="sampling temperature for 'sample' / 'beam' (see generate --temperature)")
    p.add_argument("--l2m-rerank", metavar="M2L", help="round trip: describe the hypothesis "
                   "under which this other M2L model finds the sentence likeliest, not the "
                   "L2M's likeliest (not the --m2l file)")
    p.set_defaults(func=cmd_evaluate)


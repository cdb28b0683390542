"""``motionlang train judge`` and ``motionlang evaluate-judge``: the real-motion judge.

Thin wrappers over :mod:`motionlang.models.judge.fit` (the Bandai Namco takes as labelled
21-joint motions, a plain training loop, accuracy) and :mod:`motionlang.evaluation.judge`
(recognition, FID on the judge's features, diversity and physical plausibility of generated
motions beside the real ones). The judge is trained on the Bandai Namco datasets, CC BY-NC
4.0: it and every figure made with it are for non-commercial use only; ``train judge``
writes that note into its run folder. torch is imported inside the commands only.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.cli.options import (
    dropout_float,
    frames_int,
    layers_int,
    nonneg_float,
    nonneg_int,
    output_dir,
    positive_float,
    positive_int,
    seed_int,
    size_int,
)
from motionlang.cli.train_commands import add_out_arg, model_file
from motionlang.datasets.sources import parse_source
from motionlang.errors import MotionlangError
from motionlang.training.run_log import LICENSE_FILE, log_command, write_license

BANDAI = "bandai:"
NON_COMMERCIAL = ("Trained on the Bandai Namco Research Motion Datasets (CC BY-NC 4.0): the "
                  "judge and the figures made with it are for non-commercial use only.")


def bandai_path(data: str) -> str:
    """``bandai:DIR`` (or a plain DIR) -> DIR."""
    path = parse_source(data, kind="bandai").root
    if not path.strip():
        raise MotionlangError(f"--data {data!r}: expected bandai:DIR")
    return path


# -- train judge -----------------------------------------------------------------------------
def cmd_train(args: argparse.Namespace) -> int:
    from motionlang.models.judge.fit import (
        accuracy,
        bandai_items,
        fit_judge,
        median_bones,
        primitive_items,
    )
    from motionlang.utils.atomic import atomic_write

    run = Path(args.out)
    source = bandai_path(args.data)
    config = {k: getattr(args, k) for k in ("hidden", "embed", "layers", "kernel", "dropout",
                                             "window")}
    from motionlang.models.judge.config import JudgeConfig
    JudgeConfig(contents=["x"], styles=["x"], **config)   # a bad size fails before reading
    train, val, test = (bandai_items(source, s) for s in ("train", "val", "test"))
    extra = primitive_items(args.primitives) if args.primitives else []
    if not train and not extra:
        raise MotionlangError(f"{source}: no Bandai training takes")
    run.mkdir(parents=True, exist_ok=True)
    log_command(run / "commands.jsonl", args)
    write_license(run, "judge")
    print(f"judge: {len(train)} training takes, {len(val)} validation, {len(test)} test"
          + (f"; {len(extra)} procedural primitives" if args.primitives else ""))
    if args.uniform:    # the real actors' body, not a mean with the procedural one's
        config["bones"] = median_bones(train or extra)
    def epoch_line(text: str) -> None:   # progress a log file shows too (not a bar)
        if not args.verbose:
            rec = dict(zip(text.split()[::2], text.split()[1::2]))
            text = (f"epoch {rec.get('epoch')}/{args.epochs}: validation content "
                    f"{rec.get('val_content', '-')}, style {rec.get('val_style', '-')}, "
                    f"{rec.get('seconds', '?')} s")
        print(text, flush=True)

    judge, history = fit_judge(train + extra, val, epochs=args.epochs, uniform=args.uniform,
                               batch_size=args.batch_size, lr=args.lr,
                               weight_decay=args.weight_decay, mirror=args.mirror,
                               seed=args.seed, log=epoch_line, **config)
    out = run / model_file("judge")
    judge.save(out)
    with atomic_write(run / "history.json") as fh:
        fh.write(json.dumps(history, indent=1) + "\n")
    line = f"{out}: {len(judge.config.contents)} contents, {len(judge.config.styles)} styles"
    if test:
        acc = accuracy(judge, test)
        line += (f"; on the {acc['n']} test takes content {acc['content']:.3f}, style "
                 f"{acc['style']:.3f}")
    print(line)
    print(NON_COMMERCIAL)
    return 0


def register_train(train_sub) -> None:
    """Hook of ``cli/train_commands.py``: adds ``train judge``."""
    h = "train the real-motion judge (content and style classifier) on Bandai Namco takes"
    p = train_sub.add_parser(
        "judge", help=h, description=h + f". {NON_COMMERCIAL} Splits: dataset 2's takes "
        "numbered 0 mod 5 are test, 4 mod 5 validation (picks the epoch), the rest and "
        "dataset 1 training.")
    p.add_argument("--data", required=True, metavar="bandai:DIR",
                   help="the Bandai Namco datasets (a clone of the repository, its two "
                        ".tar.xz archives, or one dataset folder); CC BY-NC 4.0")
    add_out_arg(p, "judge", f"history.json, {LICENSE_FILE} (the non-commercial licence), ")
    p.add_argument("--primitives", metavar="CORPUS",
                   help="also train on a procedural corpus' primitives that show a Bandai "
                        "action (content only)")
    p.add_argument("--as-given", dest="uniform", action="store_false",
                   help="read motions on their own bodies (default: every motion laid on "
                        "the training takes' median bone lengths, directions and gait kept, "
                        "so a body's proportions do not pass for an action)")
    from motionlang.models.judge.config import JudgeConfig  # torch-free
    d = JudgeConfig(contents=["x"], styles=["x"])
    p.add_argument("--hidden", type=size_int, default=d.hidden,
                   help="channels of the temporal convolutions")
    p.add_argument("--embed", type=size_int, default=d.embed,
                   help="size of the features FID is computed on")
    p.add_argument("--layers", type=layers_int, default=d.layers,
                   help="dilated convolutions (dilations 1, 2, 4, ...)")
    p.add_argument("--kernel", type=size_int, default=d.kernel, help="convolution kernel")
    p.add_argument("--dropout", type=dropout_float, default=d.dropout, help="dropout")
    p.add_argument("--window", type=frames_int, default=d.window,
                   help="frames (12.5 Hz) of the random crops trained on")
    p.add_argument("--epochs", type=positive_int, default=30, help="passes over the takes")
    p.add_argument("--batch-size", type=positive_int, default=32, help="takes per step")
    p.add_argument("--lr", type=positive_float, default=1e-3, help="AdamW's learning rate")
    p.add_argument("--weight-decay", type=nonneg_float, default=1e-4,
                   help="AdamW's weight decay")
    p.add_argument("--no-mirror", dest="mirror", action="store_false",
                   help="train without left/right mirrored copies of the takes")
    p.add_argument("--seed", type=seed_int, default=0,
                   help="seed of the initial weights, crops and batch order")
    p.add_argument("--verbose", action="store_true",
                   help="the training measures of every epoch (default: a short line each)")
    p.set_defaults(func=cmd_train)


# -- evaluate-judge --------------------------------------------------------------------------
def cmd_evaluate(args: argparse.Namespace) -> int:
    from motionlang.cli.models_arg import load_t2m_models
    from motionlang.decoding.t2m import FPS
    from motionlang.evaluation.judge import asked_labels, judge_table, markdown_judge_table
    from motionlang.features.foot_lock import lock_feet
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.registry import load_model
    from motionlang.utils.progress import progress

    judge = load_model(args.judge, kind="judge")
    models = load_t2m_models(args.model)
    source = bandai_path(args.data)
    real = bandai_items(source, args.split, fps=FPS)
    sentences = bandai_sentences(source, args.split, seed=args.seed)
    if not real:
        raise MotionlangError(f"{source}: no Bandai takes in the {args.split} split")
    real, sentences = real[:args.limit or None], sentences[:args.limit or None]
    asked = asked_labels(sentences)
    generated = {}
    for name, t2m in models.items():
        kw = {} if t2m.deterministic else {"seed": args.seed}   # its options: how it decodes
        raw = [t2m.positions21(s.text, max(2, len(it.positions)), **kw)
               for s, it in progress(list(zip(sentences, real)), desc=name, unit="motions")]
        # the lock is a post-process of the decoded frames: both rows from one decoding
        if args.foot_lock in ("off", "both"):
            generated[name + (" (raw)" if args.foot_lock == "both" else "")] = raw
        if args.foot_lock in ("on", "both"):
            generated[name] = [lock_feet(p, FPS) for p in raw]
    table = judge_table(judge, [it.positions for it in real],
                        [(it.content, it.style) for it in real], FPS, generated, asked, FPS,
                        rng=args.seed)
    title = (f"{len(real)} Bandai {args.split} takes of {source}, judge {args.judge} "
             f"({len(judge.config.contents)} contents, {len(judge.config.styles)} styles, "
             f"motions read {'on one body' if judge.config.bones else 'on their own bones'}); "
             "models asked one sentence per take. Ground truth: the judge's own accuracy, "
             "FID between two halves of the takes. " + NON_COMMERCIAL)
    text = markdown_judge_table(table, title)
    print(text, end="")
    if args.output:
        from motionlang.utils.atomic import atomic_write
        out = Path(args.output)
        out.mkdir(parents=True, exist_ok=True)
        with atomic_write(out / "judge_table.md") as fh:
            fh.write(text)
        report = {"data": source, "split": args.split, "judge": str(args.judge),
                  "takes": len(real), "models": dict(zip(models, args.model or [])),
                  "licence": NON_COMMERCIAL, "rows": table,
                  "sentences": [s.text for s in sentences]}
        with atomic_write(out / "judge_report.json") as fh:
            fh.write(json.dumps(report, indent=1) + "\n")
    return 0


def register(subparsers) -> None:
    from motionlang.cli.models_arg import add_model_arg
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
                   help="judge at most N takes (0: all)")
    p.add_argument("--seed", type=seed_int, default=0,
                   help="seed of the sentences, the sampling models' draws and the FID halves")
    p.add_argument("--foot-lock", choices=("on", "off", "both"), default="on",
                   help="judge the motions with feet that are down held in place, as "
                        "'motionlang generate' writes joint-position models' motions (on), "
                        "as decoded (off), or both (rows NAME and 'NAME (raw)')")
    p.add_argument("-o", "--output", metavar="DIR", type=output_dir,
                   help="write judge_table.md and judge_report.json here")
    p.set_defaults(func=cmd_evaluate)

"""``motionlang train evaluator`` and ``evaluate-t2m --protocol guo``: the text-motion
evaluator of Guo et al. 2022 and the yardstick of the text-to-motion papers.

Thin wrappers over :mod:`motionlang.training.evaluator_train` (dataset -> HumanML3D rows
and tagged captions, the shared trainer) and :mod:`motionlang.evaluation.t2m.yardstick`
(R-precision, FID, MM-Dist, Diversity, MultiModality, TMR's retrieval; one table). The
``evaluate-t2m`` parser itself is ``cli/twostream_commands.py``'s; this module adds the
options of the ``guo`` protocol to it (:func:`add_guo_args`) and runs it
(:func:`cmd_evaluate_guo`). torch is imported inside the commands only.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.cli.options import (
    dropout_float,
    int_range,
    nonneg_int,
    positive_float,
    positive_int,
    size_int,
)
from motionlang.cli.train_commands import add_out_arg, add_trainer_args, model_file, train_config
from motionlang.errors import MotionlangError
from motionlang.training.run_log import lead_process, log_command

BODIES = ("kit", "smpl")
#: options of the default (``ape``) protocol that mean nothing under ``guo``: name -> unset
APE_ONLY = {"autoencode": False, "true_start": False, "oracle": 0}
GUO_ONLY = ("evaluator", "evaluator_official", "mean", "std", "word_vectors", "m2l",
            "regenerate")   # (--fid-reference has a default: not checked)


# -- train evaluator -------------------------------------------------------------------------
def evaluator_config(args: argparse.Namespace):
    """The :class:`EvaluatorConfig` of the options (checked by the config itself)."""
    from motionlang.features.h3d_vectors import H3D_BODIES
    from motionlang.models.evaluator.config import EvaluatorConfig
    return EvaluatorConfig(
        motion_dim=H3D_BODIES[args.body].dim, drop_last=4, text_hidden=args.text_hidden,
        motion_hidden=args.motion_hidden, movement_hidden=args.movement_hidden,
        movement_latent=args.movement_latent, embed_dim=args.embed_dim,
        max_words=args.max_words, loss=args.loss, margin=args.margin,
        temperature=args.temperature, dropout=args.dropout)


def cmd_train(args: argparse.Namespace) -> int:
    import logging

    import torch

    from motionlang.datasets.sources import non_commercial
    from motionlang.datasets.splits import save_splits
    from motionlang.models.evaluator import TextMotionEvaluator
    from motionlang.training.evaluator_train import build_evaluator_data, train_evaluator
    from motionlang.training.run_files import check_resume

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    run = Path(args.out)
    # every motion on one body (the training motions' median bones) unless --as-given; a
    # resumed run keeps the body it started on (its normaliser and weights were fitted there)
    bones = "median" if args.uniform and args.body == "kit" else None
    if args.resume:
        from motionlang.training.run_files import read_training_checkpoint
        bones = read_training_checkpoint(check_resume(run, read=False))["model"]["config"].get(
            "bones")
    cfg = train_config(args, run, optimizer="adam")     # checked at once
    config = evaluator_config(args)
    lead = lead_process()
    data = build_evaluator_data(args.data, args.body, seed=args.seed,
                                max_seconds=args.max_seconds, bones=bones)
    config.bones = data.bones
    if lead:
        save_splits({s: list(dict.fromkeys(it["id"] for it in items))
                     for s, items in data.items.items()}, run / "splits")
    log_command(run / "commands.jsonl", args)
    if lead and non_commercial(args.data):
        from motionlang.training.run_log import write_license
        write_license(run, "evaluator")
    torch.manual_seed(args.seed)
    model = TextMotionEvaluator(config)
    if lead:
        print(f"evaluator ({args.body} body, {config.motion_dim} values a frame): "
              f"{len(data.items['train'])} training captions, "
              f"{sum(p.numel() for p in model.parameters()):,} parameters")
    val = data.items.get("val") or None
    # the epoch kept: the best validation R-precision top-3 (one caption per motion, batches
    # of 32), what the evaluator is for; the contrastive loss follows it badly where
    # captions repeat (Bandai's templates: its validation loss rose from epoch 1 on while
    # R-precision grew). Fewer than 32 validation motions: the validation loss.
    from motionlang.evaluation.t2m.yardstick import r_precision_miss
    select = r_precision_miss(val, seed=args.seed) if val else None
    model, history = train_evaluator(model, data.items["train"], cfg, val_items=val,
                                     body=args.body, resume=args.resume, select=select)
    if not lead:
        return 0
    if val and (run / "best.pt").is_file():   # the epoch of the lowest validation loss
        model = TextMotionEvaluator.load(run / "best.pt")
    out = run / model_file("evaluator")
    model.save(out)
    # the epoch saved: the best validation score (R-precision, else loss), else the last
    with_val = [h for h in history if h.get("val")]
    key = "select" if with_val and "select" in with_val[-1]["val"] else "loss"
    kept = min(with_val, key=lambda h: h["val"][key]) if val and with_val else \
        (history[-1] if history else {})
    v = kept.get("val", {})
    print(f"{out}: epoch {kept.get('epoch')}, train loss "
          f"{kept.get('train', {}).get('loss', float('nan')):.4g}, val loss "
          f"{v.get('loss', float('nan')):.4g}"
          + (f", val R-precision top-3 {1 - v['select']:.3f}" if "select" in v else ""))
    return 0


def register_train(train_sub) -> None:
    """Hook of ``cli/train_commands.py``: adds ``train evaluator``."""
    h = "train the text-motion evaluator of Guo et al. 2022 (the yardstick's encoders)"
    p = train_sub.add_parser(
        "evaluator", help=h, description=h + ". Motions become HumanML3D rows of --body; "
        "captions are tagged offline (or use the tags a HumanML3D folder gives); words are "
        "GloVe 6B 50d. Trained on bandai:DIR the evaluator is for non-commercial use only "
        "(CC BY-NC 4.0).")
    p.add_argument("--data", required=True, metavar="DIR",
                   help="any dataset motionlang reads: KIT-ML, a procedural corpus, a "
                        "custom folder, humanml3d:DIR / kitml-h3d:DIR, bandai:DIR")
    p.add_argument("--body", "--data-body", choices=BODIES, default="kit",
                   help="the rows' body: kit = 21 joints at 12.5 fps, 251 values (any rig); "
                        "smpl = 22 SMPL joints at 20 fps, 263 values (rigs with SMPL joints)")
    add_out_arg(p, "evaluator", "best.pt and last.pt (checkpoints), history.json, splits/, ")
    p.add_argument("--as-given", dest="uniform", action="store_false",
                   help="kit body: make each motion's rows on its own bones (default: every "
                        "motion laid on the training motions' median bone lengths, as the "
                        "public pipeline retargets to one subject, so that a body's "
                        "proportions do not pass for what it does)")
    from motionlang.models.evaluator.config import EvaluatorConfig  # torch-free
    d = EvaluatorConfig()
    for name, what in (("embed_dim", "size of the shared text/motion embedding"),
                       ("text_hidden", "GRU size of the text encoder"),
                       ("motion_hidden", "GRU size of the motion encoder"),
                       ("movement_hidden", "channels of the movement encoder's convolutions"),
                       ("movement_latent", "size of the movement codes (4 frames each)")):
        p.add_argument("--" + name.replace("_", "-"), type=size_int, default=getattr(d, name),
                       help=what)
    p.add_argument("--max-words", type=positive_int, default=d.max_words,
                   help="words kept of a caption")
    p.add_argument("--loss", choices=("hinge", "infonce"), default=d.loss,
                   help="hinge: the public contrastive loss (matched pairs near, shifted "
                        "pairs beyond --margin); infonce: cross-entropy over the batch")
    p.add_argument("--margin", type=positive_float, default=d.margin, help="the hinge's margin")
    p.add_argument("--temperature", type=positive_float, default=d.temperature,
                   help="InfoNCE's temperature")
    p.add_argument("--dropout", type=dropout_float, default=d.dropout,
                   help="dropout of the movement encoder")
    add_trainer_args(p, epochs=30, batch_size=32, grad_clip=0.5)
    p.add_argument("--max-seconds", type=positive_float, default=30.0,
                   help="drop longer motions")
    p.set_defaults(func=cmd_train)


# -- evaluate-t2m --protocol guo -------------------------------------------------------------
def add_guo_args(p: argparse.ArgumentParser) -> None:
    """The ``guo`` protocol's options of ``evaluate-t2m``."""
    g = p.add_argument_group(
        "--protocol guo", "the papers' yardstick under a text-motion evaluator; rows: ground "
        "truth, nearest neighbour, standing still, each --model (default: the packaged l2m)")
    g.add_argument("--evaluator", metavar="E",
                   help="an evaluator file or run folder (train evaluator --out)")
    g.add_argument("--evaluator-official", metavar="TAR",
                   help="instead: the public evaluator's weights (finest.tar of "
                        "EricGuo5513/text-to-motion), with --mean, --std and --word-vectors")
    g.add_argument("--mean", metavar="NPY", help="the public evaluator's mean.npy")
    g.add_argument("--std", metavar="NPY", help="the public evaluator's std.npy")
    g.add_argument("--word-vectors", metavar="TXT",
                   help="word vectors in GloVe's text format, of the evaluator's size (the "
                        "public weights: glove.6B.300d.txt; default: the built-in GloVe 50d)")
    g.add_argument("--repeats", type=positive_int, default=20,
                   help="shuffles of the test pairs; each figure is their mean ± 95 %% "
                        "interval")
    g.add_argument("--rp-batch", type=int_range(2), default=32, metavar="B",
                   help="R-precision and MM-Dist among batches of B pairs")
    g.add_argument("--multimodality", type=nonneg_int, default=0, metavar="S",
                   help="also MultiModality of the models that sample: S > 10 samples for "
                        "each of --mm-texts captions (the papers: 30 and 100; 0: not measured)")
    g.add_argument("--mm-texts", type=positive_int, default=100,
                   help="captions MultiModality samples for")
    g.add_argument("--fid-reference", choices=("train", "val"), default="train",
                   help="the real motions the ground truth's FID compares the test motions "
                        "with (val: held out like them, when the training split holds data "
                        "the test split has not, e.g. Bandai's dataset 1)")
    g.add_argument("--regenerate", action="store_true",
                   help="the models that sample (e.g. --model l2m:method=sample) generate "
                        "anew for each of the --repeats, as the papers do (that many times the "
                        "generation time); default: one generation, its pairs reshuffled")
    g.add_argument("--m2l", action="append", metavar="[NAME=]PATH",
                   help="motion to text: an M2L model (file, run folder or packaged name) "
                        "whose descriptions of the test motions are scored (BLEU@1/4, "
                        "ROUGE-L, CIDEr, their R-precision under the evaluator); repeat for "
                        "each; default the packaged m2l; 'none': no motion-to-text table")
    g.add_argument("--m2l-width", type=positive_int, default=5, metavar="W",
                   help="the M2L's beam width (its best hypothesis is scored)")


def check_protocol(args: argparse.Namespace) -> None:
    """Options of one protocol given to the other: one line naming them."""
    if args.protocol == "guo":
        wrong = [k for k, unset in APE_ONLY.items() if getattr(args, k) != unset]
        if wrong:
            raise MotionlangError(f"--{wrong[0].replace('_', '-')} applies to --protocol ape")
        if bool(args.evaluator) == bool(args.evaluator_official):
            raise MotionlangError("--protocol guo needs --evaluator E or --evaluator-official "
                                  "TAR (one of them)")
        if bool(args.evaluator_official) != bool(args.mean and args.std) or (
                args.evaluator and (args.mean or args.std)):
            raise MotionlangError("--mean and --std go with --evaluator-official (both)")
        if args.multimodality and args.multimodality <= 10:
            raise MotionlangError(f"--multimodality {args.multimodality}: need more than 10 "
                                  "samples a caption (10 pairs are drawn among them)")
    else:
        wrong = [k for k in GUO_ONLY if getattr(args, k)]
        if wrong:
            raise MotionlangError(f"--{wrong[0].replace('_', '-')} applies to --protocol guo")
        if not args.model:
            raise MotionlangError("--protocol ape needs at least one --model")


def load_evaluator(args: argparse.Namespace):
    """The evaluator of ``--evaluator`` or ``--evaluator-official`` (+ ``--mean/--std``)."""
    from motionlang.models.evaluator import TextMotionEvaluator
    from motionlang.models.registry import load_model
    vectors = None
    if args.word_vectors:
        from motionlang.models.evaluator.text import TextFileVectors
        vectors = TextFileVectors(args.word_vectors)
    if args.evaluator_official:
        model = TextMotionEvaluator.load_official(args.evaluator_official, args.mean, args.std,
                                                  vectors=vectors)
    else:
        model = load_model(args.evaluator, kind="evaluator", vectors=vectors)
    if vectors is not None and vectors.dim != model.config.word_dim:
        raise MotionlangError(f"--word-vectors {args.word_vectors}: {vectors.dim}-d words, the "
                              f"evaluator reads {model.config.word_dim}-d ones")
    return model


def cmd_evaluate_guo(args: argparse.Namespace) -> int:
    from motionlang.cli.models_arg import draws, load_t2m_models, split_label
    from motionlang.evaluation.t2m.yardstick import (
        evaluator_body,
        guo_table,
        markdown_table,
        test_pairs,
    )
    from motionlang.models.registry import load_model
    from motionlang.training.evaluator_train import build_evaluator_data

    check_protocol(args)
    evaluator = load_evaluator(args)
    body = evaluator_body(evaluator)
    specs = args.model or (["l2m"] if body == "kit" else [])
    if specs and body != "kit":
        raise MotionlangError("the models' 21-joint motions cannot be scored by an SMPL-body "
                              "(263-value) evaluator; use a kit-body (251) one")
    models = load_t2m_models(specs)
    if args.regenerate and not any(draws(m) for m in models.values()):
        raise MotionlangError("--regenerate needs a model that samples, e.g. --model "
                              "l2m:method=sample (the others give the same motions every time)")
    m2l_specs, m2l_models = m2l_specs_of(args), {}
    for spec in m2l_specs:   # loaded before the data is read: a bad --m2l fails at once
        name, path = split_label(spec)
        m2l_models[name] = load_model(path, kind="m2l")
    bones = evaluator.config.bones
    data = build_evaluator_data(args.data, body, seed=args.seed, max_seconds=args.max_seconds,
                                bones=bones)
    items = data.items.get(args.split) or []
    pairs = test_pairs(items, args.seed)[:args.limit or None]
    if len(pairs) < args.rp_batch:
        raise MotionlangError(f"{args.data}: {len(pairs)} {args.split} motions, R-precision "
                              f"needs at least --rp-batch {args.rp_batch}")
    captions = [p["caption"] for p in pairs]
    frames = [len(p["motion"]) + 1 for p in pairs]    # rows are steps between 12.5 Hz frames
    gen, samples = model_rows(args, models, captions, frames, bones)
    reference = None
    if args.fid_reference != "train":
        reference = data.items.get(args.fid_reference) or []
        if len({it["id"] for it in reference}) < 2:
            raise MotionlangError(f"--fid-reference {args.fid_reference}: {args.data} has "
                                  f"fewer than 2 {args.fid_reference} motions")
    table = guo_table(evaluator, pairs, data.items.get("train") or [], gen, samples=samples,
                      reference_items=reference, repeats=args.repeats, seed=args.seed,
                      batch_size=args.rp_batch)
    title = (f"{len(pairs)} {args.split} pairs of {args.data}, evaluator "
             f"{args.evaluator or args.evaluator_official} ({body} body"
             f"{', every motion laid on one body' if bones else ''}); mean ± 95 % "
             f"interval over {args.repeats} shuffles, R-precision in batches of "
             f"{args.rp_batch}; FID against the test motions (ground truth: test against "
             f"{'training' if args.fid_reference == 'train' else args.fid_reference} "
             "motions); retrieval (t2m R@k %, MedR) among all pairs")
    text = markdown_table(table, title)
    print(text, end="")
    m2t, m2t_text = motion_to_text(args, evaluator, data, pairs, m2l_models)
    if m2t_text:
        print("\n" + m2t_text, end="")
    if args.output:
        write_guo_files(args, Path(args.output), text + ("\n" + m2t_text if m2t_text else ""),
                        {"protocol": "guo", "data": str(args.data), "split": args.split,
                         "evaluator": str(args.evaluator or args.evaluator_official),
                         "body": body, "pairs": len(pairs), "repeats": args.repeats,
                         "rp_batch": args.rp_batch,
                         "models": {n: s for n, s in zip(models, specs)}, "rows": table,
                         "m2l": {n: s for n, s in zip(m2l_models, m2l_specs)},
                         "m2t_rows": m2t})
    return 0


def model_rows(args: argparse.Namespace, models: dict, captions: list[str], frames: list[int],
               bones=None) -> tuple[dict, dict]:
    """Each text-to-motion model's rows for the captions with its own options (a function
    of the repetition with ``--regenerate``, for the models that sample), and with
    ``--multimodality`` S samples for the first captions; laid on ``bones`` (the
    evaluator's) if given."""
    from motionlang.cli.models_arg import draws
    from motionlang.evaluation.t2m.yardstick import generated_rows
    gen = {}
    for name, m in models.items():
        if args.regenerate and draws(m):
            # a new generation for each repetition, seeds seed, seed + 1, ... (the papers')
            gen[name] = (lambda i, m=m, name=name: generated_rows(
                m, captions, frames, seed=args.seed + i, desc=f"{name} #{i + 1}",
                bones=bones))
        else:
            gen[name] = generated_rows(m, captions, frames, seed=args.seed, desc=name,
                                       bones=bones)
    samples = {}
    if args.multimodality:
        n = min(args.mm_texts, len(captions))
        for name, m in models.items():
            if m.deterministic:   # one motion a caption: nothing to measure
                continue
            samples[name] = [[generated_rows(m, [c], [f], method="sample", seed=k,
                                             desc=f"{name} sample", bones=bones)[0]
                              for k in range(args.multimodality)]
                             for c, f in zip(captions[:n], frames[:n])]
    return gen, samples


def m2l_specs_of(args: argparse.Namespace) -> list[str]:
    """The ``--m2l`` values (default the packaged m2l; ``none`` alone: none)."""
    specs = args.m2l or ["m2l"]
    return [] if specs == ["none"] else specs


def motion_to_text(args: argparse.Namespace, evaluator, data, pairs, m2l_models: dict
                   ) -> tuple[dict, str]:
    """The motion-to-text table (``evaluation.t2m.m2t``) of the ``--m2l`` models on the test
    pairs, and its Markdown ("" when there are no M2L models)."""
    if not m2l_models:
        return {}, ""
    from motionlang.evaluation.t2m.m2t import describe_motions, m2t_table
    from motionlang.evaluation.t2m.yardstick import markdown_table
    records = [data.records[p["id"]] for p in pairs]
    motions = [r.load_motion() for r in records]
    described = {name: describe_motions(m, motions, width=args.m2l_width, desc=name)
                 for name, m in m2l_models.items()}
    table, counted = m2t_table(evaluator, pairs, [r.annotations for r in records],
                               data.items.get("train") or [], described,
                               repeats=args.repeats, seed=args.seed, batch_size=args.rp_batch)
    title = (f"Motion to text, the same {len(pairs)} test motions: each row's description "
             f"(M2L: best of a beam of {args.m2l_width}) against the motion's other captions "
             f"(BLEU, ROUGE-L, CIDEr; {counted} motions have one) and ranked by the "
             f"evaluator among batches of {args.rp_batch} motions (mean ± 95 % interval "
             f"over {args.repeats} shuffles); ground truth: the pair's own caption")
    return table, markdown_table(table, title)


def write_guo_files(args: argparse.Namespace, out: Path, text: str, report: dict) -> None:
    """``t2m_guo.md``, ``t2m_guo.json`` and ``t2m_guo.png`` in ``out`` (atomic writes)."""
    from motionlang.evaluation.t2m.plots import plot_yardstick
    from motionlang.utils.atomic import atomic_write
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / "t2m_guo.md") as fh:
        fh.write(text)
    with atomic_write(out / "t2m_guo.json") as fh:
        fh.write(json.dumps(report, indent=1, default=list) + "\n")
    plot_yardstick(report["rows"], out / "t2m_guo.png", report.get("m2t_rows") or None,
                   title=f"{report['pairs']} {report['split']} pairs of {report['data']}")

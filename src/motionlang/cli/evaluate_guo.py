"""``evaluate-t2m --protocol guo``: the yardstick of the text-to-motion papers under a
text-motion evaluator (Guo et al. 2022).

The ``evaluate-t2m`` parser itself is ``cli/evaluate_t2m.py``'s; this module adds the
options of the ``guo`` protocol to it (:func:`add_guo_args`), checks which options go with
which protocol (:func:`check_protocol`) and runs it (:func:`cmd_evaluate_guo`) through
:mod:`motionlang.evaluation.t2m.guo`. ``train evaluator`` is generated from its recipe
(``recipes/evaluator.py``). torch is imported inside the commands only.
"""
from __future__ import annotations

import argparse

from motionlang.cli.config_options import add_config_options, config_from_args, option_message
from motionlang.cli.models_arg import load_t2m_models
from motionlang.errors import MotionlangError
from motionlang.evaluation.t2m import guo
from motionlang.evaluation.t2m.guo import GuoOptions  # torch-free
from motionlang.models.options import split_label
from motionlang.models.registry import load_model

#: options of the default (``ape``) protocol that mean nothing under ``guo``: name -> unset
APE_ONLY = {"autoencode": False, "true_start": False, "oracle": 0}
GUO_ONLY = ("evaluator", "evaluator_official", "mean", "std", "word_vectors", "m2l",
            "regenerate")   # (the options with a default are not checked)


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
    add_config_options(g, GuoOptions)
    g.add_argument("--m2l", action="append", metavar="[NAME=]PATH",
                   help="motion to text: an M2L model (file, run folder or packaged name) "
                        "whose descriptions of the test motions are scored (BLEU@1/4, "
                        "ROUGE-L, CIDEr, their R-precision under the evaluator); repeat for "
                        "each; default the packaged m2l; 'none': no motion-to-text table")


def check_protocol(args: argparse.Namespace):
    """Options of one protocol given to the other: one line naming them. Returns the
    ``GuoOptions`` of the options (checked under either protocol)."""
    options = config_from_args(GuoOptions, args)
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
    else:
        wrong = [k for k in GUO_ONLY if getattr(args, k)]
        if wrong:
            raise MotionlangError(f"--{wrong[0].replace('_', '-')} applies to --protocol guo")
        if not args.model:
            raise MotionlangError("--protocol ape needs at least one --model")
    return options


def m2l_models(values: list[str] | None) -> tuple[dict, dict]:
    """``{label: model}`` and ``{label: value}`` of the ``--m2l`` values (default the
    packaged m2l; ``none`` alone: none), loaded before the data is read so that a bad one
    fails at once."""
    specs = values or ["m2l"]
    models, given = {}, {}
    for spec in [] if specs == ["none"] else specs:
        name, path = split_label(spec)
        models[name], given[name] = load_model(path, kind="m2l"), spec
    return models, given


def cmd_evaluate_guo(args: argparse.Namespace) -> int:

    options = check_protocol(args)
    try:
        evaluator = guo.load_evaluator(args.evaluator, official=args.evaluator_official,
                                       mean=args.mean, std=args.std,
                                       word_vectors=args.word_vectors)
        specs = guo.model_specs(evaluator, args.model)
        models = load_t2m_models(specs)
        guo.check_models(models, options)
        m2l, m2l_given = m2l_models(args.m2l)
        run = guo.GuoRun.prepare(evaluator, args.data,
                                 evaluator_name=str(args.evaluator or args.evaluator_official),
                                 split=args.split, seed=args.seed, max_seconds=args.max_seconds,
                                 limit=args.limit, options=options)
        rows, text = run.text_to_motion(models)
        print(text, end="")
        m2t_rows, m2t_text = run.motion_to_text(m2l)
    except MotionlangError as exc:   # the options' field names -> the options
        raise MotionlangError(option_message(guo.GuoOptions, str(exc))) from None
    if m2t_text:
        print("\n" + m2t_text, end="")
        text += "\n" + m2t_text
    if args.output:
        guo.write_guo_files(args.output, text, run.report(
            rows, m2t_rows, dict(zip(models, specs)), m2l_given))
    return 0

"""``motionlang crbm generate | fill | reproduce``: the CMU subject-35 experiment of Taylor,
Hinton & Roweis 2006 (``evaluation.crbm``) on the command line. ``train crbm`` is the
family's recipe (``recipes.crbm``). ``--data`` is the folder holding
``cmu35WalkJog.mat``, ``cmu35TaylorScaleBias.mat`` and ``35.asf``.
"""
from __future__ import annotations

import argparse
import json
import sys

from motionlang.api import load_model
from motionlang.cli.config_options import add_config_options, option_fields, option_message
from motionlang.cli.options import (
    count_int,
    frames_int,
    nonneg_float,
    output_dir,
    output_file,
    seed_int,
)
from motionlang.datasets.cmu35 import load_cmu35
from motionlang.errors import MotionlangError
from motionlang.evaluation.crbm.generation import START_TRIALS, generate_from_test
from motionlang.evaluation.crbm.output import start_xz, write_fill, write_fill_figures, write_frames
from motionlang.evaluation.crbm.reproduce import (
    ReproduceConfig,
    fill_test_trial,
    format_table,
    reproduce,
)
from motionlang.models.crbm.config import SELECTED, CRBMConfig
from motionlang.recipes.crbm import DATA_HELP, MODEL_DEFAULTS, STACK_FILE, model_config


def _add_data(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", required=True, metavar="DIR", help=DATA_HELP)


def cmd_generate(args: argparse.Namespace) -> int:
    model = load_model(args.model, kind=("crbm", "crbm_stack"))
    data = load_cmu35(args.data)
    gen, report = generate_from_test(model, data, args.start, args.frames, n_gibbs=args.gibbs,
                                     seed=args.seed, hidden_noise=args.noise)
    write_frames(gen, args.output, data, args.data, name=f"crbm from {args.start}",
                 start_xz=start_xz(data, START_TRIALS[args.start]),
                 title=f"CRBM, started from {args.start}")
    print(json.dumps(report) if args.json else
          f"{args.output}: {args.frames} frames from {args.start}; walk "
          f"{report['fraction_walk']:.0%}, jog {report['fraction_jog']:.0%}, "
          f"{report['label_changes']} label changes, range excess "
          f"{report['range_excess_std']:.2f} std, forward speed (last half) "
          f"{report['forward_speed_last_half_m_s']:.2f} m/s")
    return 0


def cmd_fill(args: argparse.Namespace) -> int:
    model = load_model(args.model, kind="crbm")
    data = load_cmu35(args.data)
    part = args.part.replace("-", " ")
    res = fill_test_trial(model, data, args.trial, part, n_repeats=args.repeats,
                          n_gibbs=args.gibbs, seed=args.seed, mean_field=args.mean_field)
    write_fill(res, args.output, data, args.data, args.trial,
               title=f"{args.trial}: {part} erased from frame {res['gap_start']}")
    errs = {k: round(v, 4) for k, v in res["errors"].items()}
    print(json.dumps(errs) if args.json else
          f"{args.output}: " + ", ".join(f"{k} {v:.2f}" for k, v in errs.items()))
    return 0


def cmd_reproduce(args: argparse.Namespace) -> int:
    if args.model:
        model, config = load_model(args.model, kind="crbm"), None
    else:
        model = None
        try:   # the options of train crbm, checked by the config
            config = model_config({f.name: getattr(args, f.name)
                                   for f in option_fields(CRBMConfig)})
        except MotionlangError as exc:
            raise MotionlangError(option_message(CRBMConfig, str(exc))) from None
    cfg = ReproduceConfig(crbm=model.config if model else config, n_repeats=args.repeats,
                          n_gibbs=args.gibbs, seed=args.seed, mean_field=args.mean_field)
    result = reproduce(args.data, cfg, crbm=model, show_progress=not (args.quiet or args.json),
                       keep_fills=bool(args.plots))
    if args.plots:
        write_fill_figures(result.pop("fills"), args.plots, load_cmu35(args.data), args.data)
        result.pop("models")
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        sys.stdout.write(format_table(result))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("crbm", help="CRBM: generate, fill in, reproduce the paper",
                                   description="Conditional RBM on CMU subject 35 (Taylor et al. 2006).")
    sub = parser.add_subparsers(dest="crbm_command", metavar="ACTION")
    parser.set_defaults(func=lambda args: (parser.print_help(), 1)[1])

    g = sub.add_parser("generate", help="generate motion on-line from real starting frames")
    g.add_argument("model", metavar="MODEL", help="a CRBM (model.npz, or its run folder), or "
                   f"a two-level model ({STACK_FILE} of train crbm --level2)")
    g.add_argument("output", metavar="OUT", type=output_file,
                   help=".npy (features), .bvh/.amc, or .gif/.mp4")
    _add_data(g)
    g.add_argument("--start", choices=["walk", "jog"], default="walk",
                   help="start from the walking (35_29) or jogging (35_18) test trial")
    g.add_argument("--frames", type=frames_int, default=1000, help="frames to generate")
    g.add_argument("--noise", type=nonneg_float, default=0.0,
                   help="std of noise on the hidden biases")
    g.add_argument("--json", action="store_true", help="print the report as one JSON line")
    g.set_defaults(func=cmd_generate)

    f = sub.add_parser("fill", help="fill in an erased leg or upper body of a test trial")
    f.add_argument("model", metavar="MODEL", help="a CRBM: model.npz or its run folder")
    f.add_argument("output", metavar="OUT", type=output_file,
                   help=".png (angles plot), .npy, .bvh/.amc, or .gif/.mp4")
    _add_data(f)
    f.add_argument("--trial", choices=["35_29", "35_18"], default="35_29",
                   help="the test trial: walking (35_29) or jogging (35_18)")
    f.add_argument("--part", choices=["leg", "upper-body"], default="leg",
                   help="what is erased and filled in")
    f.add_argument("--repeats", type=count_int, default=100,
                   help="stochastic fill-ins averaged for the errors")
    for q in (g, f):
        q.add_argument("--gibbs", type=count_int, default=30, help="Gibbs updates per frame")
        q.add_argument("--seed", type=seed_int, default=0, help="seed of the Gibbs sampling")
    f.add_argument("--sampled", dest="mean_field", action="store_false",
                   help="write/plot a fill-in with sampled hiddens (default: mean-field, the "
                        "selected setting; the sampled one is scored beside it either way)")
    f.add_argument("--json", action="store_true", help="print the errors as one JSON line")
    f.set_defaults(func=cmd_fill)

    r = sub.add_parser("reproduce", help="the paper's missing-data table (trains unless --model)")
    _add_data(r)
    r.add_argument("--model", metavar="MODEL", default=None,
                   help="use this CRBM (model.npz or its run folder) instead of training")
    # the model options of train crbm, with its defaults (the selected settings)
    add_config_options(r, CRBMConfig, defaults=MODEL_DEFAULTS)
    r.add_argument("--repeats", type=count_int, default=100,
                   help="stochastic fill-ins averaged per cell")
    r.add_argument("--gibbs", type=count_int, default=SELECTED["n_gibbs"],
                   help="Gibbs updates per frame")
    r.add_argument("--plots", metavar="DIR", default=None, type=output_dir,
                   help="write Figure-4 plots and GIFs here")
    r.add_argument("--sampled", dest="mean_field", action="store_false",
                   help="report sampled-hidden fill-ins as \"CRBM\" (default: mean-field, as selected)")
    r.add_argument("--json", action="store_true", help="print the results as JSON")
    r.add_argument("--quiet", action="store_true", help="no progress")
    r.set_defaults(func=cmd_reproduce, mean_field=SELECTED["mean_field"])

"""``motionlang train crbm`` and ``motionlang crbm generate | fill | reproduce``.

Thin wrappers over :mod:`motionlang.models.crbm.model` and the CMU subject-35 experiment in
:mod:`motionlang.evaluation.crbm.reproduce`. ``--data`` is the folder holding
``cmu35WalkJog.mat``, ``cmu35TaylorScaleBias.mat`` and ``35.asf``.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from motionlang.cli.options import (
    frames_int,
    nonneg_float,
    order_int,
    output_dir,
    output_file,
    positive_float,
    positive_int,
    probability,
    seed_int,
    size_int,
)
from motionlang.cli.train_commands import add_out_arg, model_file
from motionlang.errors import MotionlangError
from motionlang.training.run_log import log_command

#: the two-level model of ``train crbm --level2``, beside the run folder's model.npz
STACK_FILE = "stack.npz"
MOTION_EXTENSIONS = (".bvh", ".amc")
RENDER_EXTENSIONS = (".gif", ".mp4")


def _add_data(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", required=True, metavar="DIR",
                   help="folder with cmu35WalkJog.mat, cmu35TaylorScaleBias.mat and 35.asf")


def _add_crbm_options(p: argparse.ArgumentParser) -> None:
    from motionlang.models.crbm.config import CRBMConfig
    d = CRBMConfig()
    p.add_argument("--hidden", type=size_int, default=d.n_hidden,
                   help="hidden units")
    p.add_argument("--order", type=order_int, default=d.order,
                   help="frames of past that condition each frame")
    p.add_argument("--epochs", type=positive_int, default=d.epochs,
                   help="passes over the data")
    p.add_argument("--batch-size", type=positive_int, default=d.batch_size,
                   help="frames per contrastive-divergence update")
    p.add_argument("--lr", type=positive_float, default=d.lr,
                   help="learning rate (of the autoregressive weights too)")
    p.add_argument("--momentum", type=probability, default=d.momentum,
                   help="momentum of the weight updates")
    p.add_argument("--weight-decay", type=nonneg_float, default=d.weight_decay,
                   help="L2 weight decay of W and B")
    p.add_argument("--ar-weight-decay", type=nonneg_float, default=d.weight_decay_autoregressive,
                   help="weight decay of the autoregressive weights A")
    p.add_argument("--history-noise", type=nonneg_float, default=d.history_noise, metavar="STD",
                   help="noise on the past frames while training (normalised units; not in "
                        "the paper)")
    p.add_argument("--seed", type=seed_int, default=d.seed,
                   help="seed of the initial weights and the batch order")


def _crbm_config(args: argparse.Namespace):
    from motionlang.models.crbm.config import CRBMConfig
    return CRBMConfig(n_hidden=args.hidden, order=args.order, epochs=args.epochs,
                      batch_size=args.batch_size, lr=args.lr, lr_autoregressive=args.lr,
                      momentum=args.momentum, weight_decay=args.weight_decay,
                      weight_decay_autoregressive=args.ar_weight_decay, seed=args.seed,
                      history_noise=args.history_noise)


def _load_model(path: str, allow_stack: bool = False):
    """A CRBM checkpoint (or, where allowed, a two-level one written by --level2)."""
    from motionlang.models.crbm.model import CRBM
    from motionlang.models.crbm.stack import CRBMStack
    from motionlang.models.registry import resolve
    path = resolve(path)   # a run folder -> its model.npz
    if allow_stack:
        try:
            with np.load(path, allow_pickle=False) as z:
                is_stack = "kind" in z.files
        except (OSError, ValueError) as exc:
            raise MotionlangError(f"{path}: not a model checkpoint ({exc})") from exc
        if is_stack:
            return CRBMStack.load(path)
    return CRBM.load(path)


def _write_frames(frames: np.ndarray, out: Path, data, data_dir: str, *, name: str,
                  start_xz=(0.0, 0.0), title: str | None = None, compare: np.ndarray | None = None
                  ) -> None:
    """Write (T, 59) model features as .npy, a motion file (.bvh/.amc) or an animation."""
    from motionlang.evaluation.crbm.reproduce import frames_to_motion
    ext = out.suffix.lower()
    if ext == ".npy":
        from motionlang.utils.atomic import atomic_write
        with atomic_write(out, "wb") as fh:
            np.save(fh, frames)
        return
    if ext not in MOTION_EXTENSIONS + RENDER_EXTENSIONS:
        raise MotionlangError(f"{out}: output must be .npy, .bvh, .amc, .gif or .mp4")
    asf = Path(data_dir) / "35.asf"
    motion = frames_to_motion(frames, data, asf, start_xz=start_xz, name=name)
    if ext in MOTION_EXTENSIONS:
        from motionlang.formats import write_motion
        write_motion(motion, out)
        return
    from motionlang.rendering import render_animation
    if compare is None:
        render_animation(motion, out, title=title)
    else:
        truth = frames_to_motion(compare, data, asf, start_xz=start_xz, name="true")
        render_animation([truth, motion], out, title=title, labels=["true", name])


# ------------------------------------------------------------------ train crbm
def cmd_train(args: argparse.Namespace) -> int:
    from motionlang.evaluation.crbm.fill import load_cmu35
    from motionlang.evaluation.crbm.reproduce import model_frames
    from motionlang.models.crbm.model import CRBM
    config = _crbm_config(args)   # checked before the data is read
    out = Path(args.out)
    data = load_cmu35(args.data)
    seqs = [model_frames(c) for c in data.train]
    log_command(out / "commands.jsonl", args)
    model = CRBM(config, 59).fit(seqs, show_progress=not args.quiet)
    model.save(out / model_file("crbm"))
    print(f"{out / model_file('crbm')}: {model.describe()}")
    if args.level2:
        from motionlang.models.crbm.stack import CRBMStack
        # level 2's visibles are hidden probabilities in [0, 1]: level 1's noise (normalised
        # units) does not carry over
        cfg2 = dataclasses.replace(model.config, visible="binary", n_hidden=args.level2_hidden,
                                   order=args.level2_order, history_noise=0.0)
        stack = CRBMStack.fit(model, seqs, cfg2, show_progress=not args.quiet)
        stack.save(out / STACK_FILE)
        print(f"{out / STACK_FILE}: two-level model, level 2 {stack.level2.describe()}")
    return 0


# ------------------------------------------------------------------ crbm generate
def cmd_generate(args: argparse.Namespace) -> int:
    from motionlang.evaluation.crbm.fill import load_cmu35
    from motionlang.evaluation.crbm.generation import StyleLabeller, forward_speed
    from motionlang.evaluation.crbm.reproduce import model_frames
    model = _load_model(args.model, allow_stack=True)
    base = getattr(model, "level1", model)       # a two-level model generates through both
    data = load_cmu35(args.data)
    trial = {"walk": "35_29", "jog": "35_18"}[args.start]
    n = getattr(model, "n_init", base.config.order)
    init = model_frames(data.test[trial])[:n]
    gen = model.generate(init, args.frames, n_gibbs=args.gibbs, seed=args.seed,
                         hidden_noise=args.noise)
    gen = gen[0] if gen.ndim == 3 else gen
    lab = StyleLabeller(data, base.mean, base.std)
    labels = lab(gen[n:])
    switches = int((labels[1:] != labels[:-1]).sum())
    report = {"frames": args.frames, "start_style": args.start,
              "fraction_walk": float((labels == "walk").mean()),
              "fraction_jog": float((labels == "jog").mean()),
              "label_changes": switches, "range_excess_std": lab.range_excess(gen[n:]),
              "forward_speed_last_half_m_s": forward_speed(gen[n:][-args.frames // 2:])}
    _write_frames(gen, Path(args.output), data, args.data, name=f"crbm from {args.start}",
                  start_xz=tuple(data.test[trial][0, [0, 2]]), title=f"CRBM, started from {args.start}")
    print(json.dumps(report) if args.json else
          f"{args.output}: {args.frames} frames from {args.start}; walk {report['fraction_walk']:.0%}, "
          f"jog {report['fraction_jog']:.0%}, {switches} label changes, range excess "
          f"{report['range_excess_std']:.2f} std, forward speed (last half) "
          f"{report['forward_speed_last_half_m_s']:.2f} m/s")
    return 0


# ------------------------------------------------------------------ crbm fill
def cmd_fill(args: argparse.Namespace) -> int:
    from motionlang.evaluation.crbm.fill import load_cmu35
    from motionlang.evaluation.crbm.reproduce import ReproduceConfig, fill_trial, model_frames
    from motionlang.models.crbm.ar import ARConfig, ARModel
    model = _load_model(args.model)
    data = load_cmu35(args.data)
    ar = ARModel(ARConfig(order=model.config.order), 59).fit([model_frames(c) for c in data.train])
    cfg = ReproduceConfig(crbm=model.config, n_repeats=args.repeats, n_gibbs=args.gibbs, seed=args.seed,
                          mean_field=args.mean_field)
    part = args.part.replace("-", " ")
    res = fill_trial(data, args.trial, part, model, ar, cfg)
    out = Path(args.output)
    title = f"{args.trial}: {part} erased from frame {res['gap_start']}"
    if out.suffix.lower() == ".png":
        from motionlang.evaluation.crbm.plots import plot_fill
        plot_fill(res, out, title=title)
    else:
        frames = model_frames(data.test[args.trial])
        fd = res["erased_dims59"]
        frames[:, fd] = res["crbm_model_frames"][0][:, fd]   # unfolded angles
        _write_frames(frames, out, data, args.data, name="CRBM fill-in",
                      start_xz=tuple(data.test[args.trial][0, [0, 2]]), title=title,
                      compare=model_frames(data.test[args.trial]))
    errs = {k: round(v, 4) for k, v in res["errors"].items()}
    print(json.dumps(errs) if args.json else f"{out}: " + ", ".join(f"{k} {v:.2f}" for k, v in errs.items()))
    return 0


# ------------------------------------------------------------------ crbm reproduce
def cmd_reproduce(args: argparse.Namespace) -> int:
    from motionlang.evaluation.crbm.reproduce import ReproduceConfig, format_table, reproduce
    model = _load_model(args.model) if args.model else None
    cfg = ReproduceConfig(crbm=model.config if model else _crbm_config(args),
                          n_repeats=args.repeats, n_gibbs=args.gibbs, seed=args.seed,
                          mean_field=args.mean_field)
    result = reproduce(args.data, cfg, crbm=model, show_progress=not (args.quiet or args.json),
                       keep_fills=bool(args.plots))
    if args.plots:
        from motionlang.evaluation.crbm.plots import plot_fill
        folder = Path(args.plots)
        for (trial, part), res in result.pop("fills").items():
            slug = f"{trial}_{part.replace(' ', '_')}"
            plot_fill(res, folder / f"{slug}.png", title=f"{trial}: {part} erased")
            crbm_frames = res["crbm_model_frames"][0]   # unfolded angles (knees past 90 deg)
            _gif_of_fill(trial, res, crbm_frames, folder / f"{slug}.gif", args)
        result.pop("models")
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        sys.stdout.write(format_table(result))
    return 0


def _gif_of_fill(trial: str, res: dict, crbm59: np.ndarray, path: Path, args) -> None:
    """True vs CRBM-filled motion side by side (``crbm59``: (T, 59) model-space frames)."""
    from motionlang.evaluation.crbm.fill import load_cmu35
    from motionlang.evaluation.crbm.reproduce import model_frames
    data = load_cmu35(args.data)
    truth = model_frames(data.test[trial])
    filled = truth.copy()
    fd = res["erased_dims59"]
    filled[:, fd] = crbm59[:, fd]
    _write_frames(filled, path, data, args.data, name="CRBM fill-in",
                  start_xz=tuple(data.test[trial][0, [0, 2]]),
                  title=f"{trial}: gap from frame {res['gap_start']}", compare=truth)


# ------------------------------------------------------------------ registration
def register_train(train_sub: argparse._SubParsersAction) -> None:
    from motionlang.models.crbm.config import CRBMConfig
    d = CRBMConfig()
    p = train_sub.add_parser("crbm", help="train a conditional RBM on CMU subject 35 walk/jog",
                             description="Train a CRBM (Taylor et al. 2006) on the 31 training trials.")
    _add_data(p)
    add_out_arg(p, "crbm", f"{STACK_FILE} (with --level2), ")
    _add_crbm_options(p)
    p.add_argument("--level2", action="store_true",
                   help=f"also train a second level on the hidden activations; the two-level "
                        f"model is OUT/{STACK_FILE}")
    p.add_argument("--level2-hidden", type=size_int, default=d.n_hidden,
                   help="hidden units of the second level")
    p.add_argument("--level2-order", type=order_int, default=d.order,
                   help="frames of past of the second level")
    p.add_argument("--quiet", action="store_true", help="no progress")
    from motionlang.evaluation.crbm.reproduce import SELECTED
    # defaults: the paper's sizes with the settings selected on held-out training trials
    p.set_defaults(func=cmd_train, epochs=SELECTED["epochs"], lr=SELECTED["lr"],
                   weight_decay=SELECTED["weight_decay"],
                   ar_weight_decay=SELECTED["weight_decay_autoregressive"],
                   history_noise=SELECTED["history_noise"])


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
    g.add_argument("--gibbs", type=positive_int, default=30, help="Gibbs updates per frame")
    g.add_argument("--seed", type=seed_int, default=0, help="seed of the Gibbs sampling")
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
    f.add_argument("--repeats", type=positive_int, default=100,
                   help="stochastic fill-ins averaged for the errors")
    f.add_argument("--gibbs", type=positive_int, default=30, help="Gibbs updates per frame")
    f.add_argument("--seed", type=seed_int, default=0, help="seed of the Gibbs sampling")
    f.add_argument("--sampled", dest="mean_field", action="store_false",
                   help="write/plot a fill-in with sampled hiddens (default: mean-field, the "
                        "selected setting; the sampled one is scored beside it either way)")
    f.add_argument("--json", action="store_true", help="print the errors as one JSON line")
    f.set_defaults(func=cmd_fill)

    r = sub.add_parser("reproduce", help="the paper's missing-data table (trains unless --model)")
    _add_data(r)
    r.add_argument("--model", metavar="MODEL", default=None,
                   help="use this CRBM (model.npz or its run folder) instead of training")
    _add_crbm_options(r)
    r.add_argument("--repeats", type=positive_int, default=100,
                   help="stochastic fill-ins averaged per cell")
    r.add_argument("--gibbs", type=positive_int, default=30, help="Gibbs updates per frame")
    r.add_argument("--plots", metavar="DIR", default=None, type=output_dir,
                   help="write Figure-4 plots and GIFs here")
    r.add_argument("--sampled", dest="mean_field", action="store_false",
                   help="report sampled-hidden fill-ins as \"CRBM\" (default: mean-field, as selected)")
    r.add_argument("--json", action="store_true", help="print the results as JSON")
    r.add_argument("--quiet", action="store_true", help="no progress")
    from motionlang.evaluation.crbm.reproduce import SELECTED
    # the experiment's defaults are the settings selected on held-out training trials
    r.set_defaults(func=cmd_reproduce, epochs=SELECTED["epochs"], lr=SELECTED["lr"],
                   weight_decay=SELECTED["weight_decay"], gibbs=SELECTED["n_gibbs"],
                   ar_weight_decay=SELECTED["weight_decay_autoregressive"],
                   history_noise=SELECTED["history_noise"], mean_field=SELECTED["mean_field"])

"""``motionlang describe MOTION`` and ``motionlang generate TEXT``: the packaged (or any)
motion-to-language and text-to-motion models on motion files of any rig.

Thin wrappers over :mod:`motionlang.api` (rigs, start poses, positions to Motions) and
:mod:`motionlang.decoding`.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from motionlang.cli.options import (
    frames_int,
    nonneg_float,
    nonneg_int,
    output_file,
    positive_float,
    seed_int,
    width_int,
)
from motionlang.errors import MotionlangError

MOTION_OUT = (".bvh", ".xml", ".amc")
RENDER_OUT = (".gif", ".mp4")


def add_rank_arg(p: argparse.ArgumentParser, default: str) -> None:
    """``--rank``: how a description beam is ordered (the names of
    ``decoding.seq2seq.RANKS``, not imported here: that would load torch for every command)."""
    p.add_argument("--rank", choices=("logp", "mbr"), default=default,
                   help="order of the beam's sentences: mbr puts first the one the beam "
                        "agrees on most (mean sentence BLEU against the beam, "
                        "decoding/mbr.py), logp the likeliest (the paper's; it favours the "
                        f"shortest phrasing) (default: {default})")


def check_length_penalty(alpha: float) -> None:
    if not (math.isfinite(alpha) and alpha >= 0):
        raise MotionlangError(f"--length-penalty must be a finite number >= 0, got {alpha}")


def cmd_describe(args: argparse.Namespace) -> int:
    from motionlang.cli.motion_commands import load_input
    from motionlang.decoding.seq2seq import describe
    from motionlang.models.registry import load_model

    check_length_penalty(args.length_penalty)
    model = load_model(args.model, kind="m2l")
    hyps = describe(model, load_input(args), width=args.width,
                    length_penalty=args.length_penalty, rank=args.rank)
    if args.json:
        print(json.dumps([{"rank": i + 1, "text": t, "log_p": s} for i, (t, s) in
                          enumerate(hyps)], indent=1))
    else:
        for i, (text, score) in enumerate(hyps, 1):
            print(f"{i}. log P = {score:8.3f}  {text}")
    return 0


def _read_rig(args: argparse.Namespace, out: Path):
    """The ``--rig`` motion file (its skeleton is the target of a .bvh output), checked
    before anything is generated, or None."""
    if args.rig is None:
        if args.rig_joint_map is not None:
            raise MotionlangError("--rig-joint-map needs --rig")
        return None
    if out.suffix.lower() != ".bvh":
        raise MotionlangError(f"{out}: --rig writes .bvh files; got {out.suffix or 'none'!r}")
    from motionlang.api import load_rig
    return load_rig(args.rig, args.rig_joint_map)


def _on_rig(result, fps: float, rig) -> tuple:
    """Generated positions (T, 21, 3) at ``fps`` or a Motion -> (Motion on ``rig``'s
    skeleton, note on how far its body joints are from the generated ones)."""
    from motionlang.api import body_motion
    motion, err = body_motion(result, fps, rig)
    err = err * 1000.0
    return motion, (f" (on the rig of {rig.meta.get('path', rig.name)}: body joints "
                    f"{err.mean():.1f} mm from the generated ones on average, at most "
                    f"{err.max():.0f} mm)")


def _write(result, path: Path, title: str, fps: float, rig=None) -> str:
    """A generated Motion, or 21-joint positions (T, 21, 3) at ``fps`` Hz, to ``path``:
    .npz (positions and fps), .bvh (a Motion as it is; positions on a 21-joint skeleton
    fitted to them), .xml / .amc (Motions on such skeletons only), .gif / .mp4 animation or
    .png pose strip.

    Returns a note for the user ("" or how far a fitted skeleton is from the positions)."""
    from motionlang.kinematics import Motion
    ext = path.suffix.lower()
    note = ""
    if rig is not None:
        result, note = _on_rig(result, fps, rig)
    if ext == ".npz":
        from motionlang.utils.atomic import atomic_write
        data = {"positions": result, "fps": np.float64(fps)} if isinstance(result, np.ndarray) \
            else {"positions": result.positions(), "fps": np.float64(result.fps)}
        with atomic_write(path, "wb") as fh:
            np.savez(fh, **data)
        return note
    if ext not in MOTION_OUT + RENDER_OUT + (".png",):
        raise MotionlangError(f"{path}: output must be .bvh, .xml, .amc, .gif, .mp4, .png "
                              "or .npz")
    if not isinstance(result, Motion):
        if ext in MOTION_OUT:
            if ext != ".bvh":
                raise MotionlangError(f"{path}: this model's features decode to joint "
                                      "positions; write .bvh, .npz, .gif, .mp4 or .png")
            # joint angles fitted to the 21 positions (bone lengths made constant)
            from motionlang.api import body_motion
            result, err = body_motion(result, fps, name=path.stem)
            err = err * 1000.0
            note = (f" (joints {err.mean():.1f} mm from the generated ones on average, "
                    f"at most {err.max():.0f} mm: bone lengths held at their medians, "
                    "pelvis and neck turned by least squares)")
        else:
            from motionlang.rendering.scene import kit21_scene
            result = kit21_scene(result, fps)
    if ext in MOTION_OUT:
        from motionlang.formats import write_motion
        write_motion(result, path)
    elif ext == ".png":
        from motionlang.rendering import render_strip
        render_strip(result, path, title=title)
    else:
        from motionlang.rendering import render_animation
        render_animation(result, path, title=title)
    return note


def cmd_generate(args: argparse.Namespace) -> int:
    # any text-to-motion checkpoint: L2M (seq2seq) or the two-stream model
    from motionlang.decoding.t2m import text_to_motion
    from motionlang.models.registry import TEXT_TO_MOTION, load_model

    if args.temperature != 1.0 and args.method == "mean":
        raise MotionlangError("--temperature applies to 'sample' and 'beam'; mean decoding "
                              "draws nothing")
    model = text_to_motion(load_model(args.model, kind=TEXT_TO_MOTION))
    if args.temperature != 1.0 and model.deterministic:
        raise MotionlangError("--temperature applies to models that sample; this "
                              f"{model.model.kind} model is deterministic")
    unknown = model.unknown_words(args.text)
    if unknown:
        print(f"motionlang generate: warning: the model does not know "
              f"{', '.join(repr(w) for w in unknown)}; each is read as an unknown word "
              f"(its vocabulary: {len(model.model.vocab)} words)", file=sys.stderr)
    if args.method is None:   # how the model was trained to continue its own frames
        args.method = model.default_method()
        if args.method == "mean" and args.temperature != 1.0:
            raise MotionlangError("--temperature: this model generates with mean decoding "
                                  "(trained on its expected frames); add --method sample")
    extra = {}
    if args.rerank:
        if model.deterministic or args.method == "mean" or args.width < 2:
            raise MotionlangError("--rerank ranks several L2M motions: an L2M model with "
                                  "--method sample or beam and -w 2 or more")
        from motionlang.decoding.rerank import check_same_features
        extra["reranker"] = load_model(args.rerank, kind="m2l")
        check_same_features(model.model, extra["reranker"], f"--rerank {args.rerank}")
    out = Path(args.output)
    rig = _read_rig(args, out)
    if args.start_from:
        from motionlang.api import first_frame
        extra["first_frame"] = first_frame(model, args.start_from, args.joint_map)
    hyps = model.hypotheses(args.text, width=args.width, method=args.method, seed=args.seed,
                        max_frames=args.max_frames, min_frames=args.min_frames,
                        length_norm=args.length_norm, temperature=args.temperature,
                        foot_lock=not args.no_foot_lock, **extra)
    # rate of position outputs: the two-stream model's 12.5 Hz, else the model's features'
    fps = model.fps
    for i, (result, score) in enumerate(hyps, 1):
        n = len(result.joint_angles) if hasattr(result, "joint_angles") else len(result)
        # the two-stream model is deterministic: it has no likelihood to rank by
        likelihood = "" if math.isnan(score) else \
            f" log P(text | motion) = {score:8.2f} " if args.rerank else f" log L = {score:10.2f} "
        line = f"{i}.{likelihood} {n} frames"
        if i == 1 or args.all:
            path = out if i == 1 else out.with_name(f"{out.stem}_{i}{out.suffix}")
            note = _write(result, path, f"{args.text} (#{i})", fps, rig)
            line += f"  -> {path}{note}"
        print(line)
    return 0



def register(subparsers) -> None:
    from motionlang.cli.motion_commands import add_input_args, add_joint_map_arg
    p = subparsers.add_parser("describe", help="describe a motion in English (M2L, beam search)")
    add_input_args(p)
    from motionlang.models.registry import licence_note
    p.add_argument("--model", default="m2l", metavar="MODEL",
                   help="a packaged model's name, an M2L model file or a training run folder "
                        "('motionlang models' lists the packaged ones; "
                        f"{licence_note('m2l')}; any model trained on Bandai Namco data is "
                        "for non-commercial use only, CC BY-NC 4.0)")
    p.add_argument("-w", "--width", type=width_int, default=5,
                   help="beam width = hypotheses shown")
    p.add_argument("--length-penalty", type=nonneg_float, default=0.0, metavar="ALPHA",
                   help="beam search ranks by log P / length**ALPHA (default 0: total log P, "
                        "the paper's; no effect with -w 1); with --rank mbr it only changes "
                        "which sentences the beam keeps")
    add_rank_arg(p, "mbr")
    p.add_argument("--json", action="store_true", help="print the hypotheses as JSON")
    p.set_defaults(func=cmd_describe)
    p = subparsers.add_parser("generate", help="generate a motion from English (L2M)")
    p.add_argument("text", help="sentence, e.g. \"a person waves with the left hand\"")
    p.add_argument("-o", "--output", required=True, type=output_file,
                   help="out.gif, .mp4 (animation), .png (pose strip), .bvh (joint angles; "
                        "for position models such as two-stream fitted on a 21-joint "
                        "skeleton) or .npz (joint positions and fps)")
    p.add_argument("--model", default="l2m", metavar="MODEL",
                   help="a packaged model's name, an L2M or two-stream model file or a "
                        "training run folder ('motionlang models' lists the packaged ones; "
                        f"{licence_note('l2m')}; any model trained on Bandai Namco data is "
                        "for non-commercial use only, CC BY-NC 4.0)")
    p.add_argument("-w", "--width", type=width_int, default=5,
                   help="hypotheses (samples or beam width)")
    p.add_argument("--method", choices=("sample", "beam", "mean"), default=None,
                   help="W ancestral samples, the paper's sampled beam (ranked by likelihood, "
                        "it favours standing still), or the mixture's expected frames "
                        "(default: the model's own way: mean for models trained on their "
                        "expected frames or on joint positions, such as the packaged L2M; "
                        "sample for joint-angle models)")
    p.add_argument("--seed", type=seed_int, default=0,
                   help="seed of the sampling (sample and beam decoding)")
    p.add_argument("--max-frames", type=frames_int, default=None,
                   help="length cap in model frames (default: the model's); a two-stream "
                        "model, or an L2M trained with --progress-input, generates exactly "
                        "this many (default: the length its length model predicts for the "
                        "sentence; a two-stream model without one: 125 = 10 s)")
    p.add_argument("--min-frames", type=nonneg_int, default=5,
                   help="no end-of-motion before this many model frames (default 5)")
    p.add_argument("--length-norm", action="store_true",
                   help="rank hypotheses (beam, sample) by log likelihood per frame (default: total)")
    p.add_argument("--temperature", type=positive_float, default=1.0, metavar="TAU",
                   help="sample (beam, sample) from the mixture sharpened by TAU: weights "
                        "softmax(logits / TAU), deviations x TAU (default 1: as trained)")
    p.add_argument("--rerank", metavar="M2L", help="rank the W motions by this M2L model's "
                   "log P(text | motion) instead of their own likelihood (L2M, sample or beam)")
    p.add_argument("--no-foot-lock", action="store_true",
                   help="keep the model's frames as decoded (default: the body moves "
                        "with the feet that are down instead of sliding over them, those "
                        "feet are held in place where the leg can reach and the knees "
                        "follow, and a foot under the floor is raised onto it; "
                        "joint-position models such as the packaged ones)")
    p.add_argument("--all", action="store_true", help="write every hypothesis (OUT_2, ...)")
    p.add_argument("--rig", metavar="FILE.bvh", default=None,
                   help="write the .bvh on this rig (a BVH file of yours: its skeleton, "
                        "joint names, units, rest pose and channel layout), retargeted from "
                        "the 21-joint body (default: the 21-joint body itself). Needs joints "
                        "that turn about 3 axes, as BVH rigs have; not ASF or MMM hinges")
    p.add_argument("--rig-joint-map", metavar="MAP.json", default=None,
                   help="how the --rig maps onto the 21-joint body, if no built-in map fits")
    p.add_argument("--start-from", metavar="FILE", default=None,
                   help="begin every motion with the first pose of this motion file (any "
                        "rig that maps onto the 21-joint body; L2M models)")
    add_joint_map_arg(p)   # for --start-from
    p.set_defaults(func=cmd_generate)

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

from motionlang.api import WordsRead, generate_hypotheses, load_rig, write_result
from motionlang.cli.config_options import add_config_options, config_from_args, given_options
from motionlang.cli.motion_commands import add_input_args, add_joint_map_arg, load_input
from motionlang.cli.options import (
    frames_int,
    nonneg_int,
    output_file,
    seed_int,
)
from motionlang.errors import MotionlangError
from motionlang.library.compose import compose_to
from motionlang.library.describe import (
    DescribeOptions,
    ReadOptions,
    describe_run,
    describer,
    printed,
)
from motionlang.models.registry import licence_note
from motionlang.models.seq2seq.config import L2MOptions
from motionlang.rendering.output import check_result_path


def cmd_describe(args: argparse.Namespace) -> int:
    options = config_from_args(DescribeOptions, args)
    if args.output is None and len(args.input) == 1 and not Path(args.input[0]).is_dir():
        return _describe_one(args, options)
    read = ReadOptions(args.asf, args.source_fps, args.sequence or 1, args.joint_map)
    run = describe_run(args.input, args.model, options, read=read)   # all checked first
    if args.output is None:
        for record in run.records():
            print(json.dumps(record, ensure_ascii=False), flush=True)
        return 0
    n, errors = run.write(args.output)
    print(f"{args.output}: {n - errors} of {n} files described" +
          (f"; {errors} could not be (their \"error\" says why)" if errors else ""))
    return 0


def _describe_one(args: argparse.Namespace, options) -> int:
    """One motion file, printed: its sentences, or with --segments its timeline."""

    d = describer(args.model, options)   # a missing model is named first
    print(printed(d, load_input(args, args.input[0]), as_json=args.json))
    return 0


def cmd_generate(args: argparse.Namespace) -> int:
    import warnings


    out = Path(args.output)
    check_result_path(out, rig=args.rig is not None)   # before the model is read
    if args.rig_joint_map is not None and args.rig is None:
        raise MotionlangError("--rig-joint-map needs --rig")
    if args.joint_map is not None and args.start_from is None and args.keep is None:
        raise MotionlangError("--joint-map maps the motion of --start-from or --keep; for "
                              "the rig to write onto, use --rig with --rig-joint-map")
    rig = None if args.rig is None else load_rig(args.rig, args.rig_joint_map)
    if args.library is not None:
        print(compose_to(args.text, args.library, out, rig=rig))
        return 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        hyps, fps = generate_hypotheses(
            args.text, args.model, seed=args.seed, max_frames=args.max_frames,
            min_frames=args.min_frames, start_from=args.start_from, joint_map=args.joint_map,
            foot_lock=not args.no_foot_lock, keep=args.keep,
            **given_options(L2MOptions, args))
    for w in caught:   # what it read as what is a note, not a warning
        note = "" if issubclass(w.category, WordsRead) else "warning: "
        print(f"motionlang generate: {note}{w.message}", file=sys.stderr)
    for i, (result, score) in enumerate(hyps, 1):
        n = len(result.joint_angles) if hasattr(result, "joint_angles") else len(result)
        # a deterministic model (two-stream) has no likelihood to rank by
        likelihood = "" if math.isnan(score) else \
            f" log P(text | motion) = {score:8.2f} " if args.rerank else f" log L = {score:10.2f} "
        line = f"{i}.{likelihood} {n} frames"
        if i == 1 or args.all:
            path = out if i == 1 else out.with_name(f"{out.stem}_{i}{out.suffix}")
            note = write_result(result, path, fps=fps, title=f"{args.text} (#{i})", rig=rig)
            line += f"  -> {path}{note}"
        print(line)
    return 0


def _add_model_arg(p: argparse.ArgumentParser, default: str | None, packaged: str,
                   files: str) -> None:
    p.add_argument("--model", default=default, metavar="MODEL",
                   help=f"a packaged model's name, {files} or a training run folder "
                        f"(default: {packaged}; 'motionlang models' lists the packaged ones; "
                        f"{licence_note(packaged)}; any model trained on Bandai Namco data is "
                        "for non-commercial use only, CC BY-NC 4.0)")


def register(subparsers) -> None:
    p = subparsers.add_parser("describe", help="describe motions in English: a file, a "
                              "library (-o captions.jsonl), long takes as timelines")
    add_input_args(p, many=True)
    _add_model_arg(p, None, "m2l", "an M2L model file (with --bank: one that encodes "
                   "sentences and motions, default the packaged one)")
    add_config_options(p, DescribeOptions)
    p.add_argument("-o", "--output", type=output_file, metavar="FILE.jsonl",
                   help="write one JSON line a file here: {\"file\", \"sentences\": [{\"text\", "
                        "\"log_p\"}]}, with --segments {\"file\", \"segments\": [{\"start\", "
                        "\"end\", \"text\", \"log_p\"}]}, or {\"file\", \"error\"}; several files "
                        "or a folder without -o: the same lines to stdout")
    p.add_argument("--json", action="store_true", help="print JSON: a list of the sentences "
                   "(or --segments), with --explain an object {sentences|segments, evidence}")
    p.set_defaults(func=cmd_describe)
    p = subparsers.add_parser("generate", help="generate a motion from English (L2M)")
    p.add_argument("text", help="sentence, e.g. \"a person waves with the left hand\"")
    p.add_argument("-o", "--output", required=True, type=output_file,
                   help="out.gif, .mp4 (animation), .png (pose strip), .bvh or .glb / "
                        ".gltf (joint angles; for position models such as two-stream fitted "
                        "on a 21-joint skeleton; glTF in metres, Y up, with a stick mesh) "
                        "or .npz (joint positions and fps)")
    _add_model_arg(p, "l2m", "l2m", "an L2M or two-stream model file")
    # the decode options: L2MOptions' fields (a masked model takes those of its own it has)
    add_config_options(p, L2MOptions, unset=True)
    p.add_argument("--seed", type=seed_int, default=0,
                   help="seed of the sampling (sample and beam decoding)")
    p.add_argument("--max-frames", type=frames_int, default=None,
                   help="length cap in model frames (default: the model's); a two-stream "
                        "model, or an L2M trained with --progress-input, generates exactly "
                        "this many (default: the length its length model predicts for the "
                        "sentence; a two-stream model without one: 125 = 10 s)")
    p.add_argument("--min-frames", type=nonneg_int, default=5,
                   help="no end-of-motion before this many model frames (default 5)")
    p.add_argument("--no-foot-lock", action="store_true",
                   help="keep the model's frames as decoded (default: the body moves with "
                        "the feet that are down instead of sliding over them, those feet are "
                        "held in place where the leg can reach and the knees follow, and a "
                        "foot under the floor is raised onto it; joint-position models)")
    p.add_argument("--all", action="store_true", help="write every hypothesis (OUT_2, ...)")
    p.add_argument("--rig", metavar="FILE.bvh", default=None,
                   help="write the .bvh / .glb on this rig (a BVH file of yours: its skeleton, "
                        "joint names, units, rest pose and channel layout), retargeted from the "
                        "21-joint body (default: the 21-joint body itself). Needs joints that "
                        "turn about 3 axes, as BVH rigs have; not ASF or MMM hinges")
    p.add_argument("--rig-joint-map", metavar="MAP.json", default=None,
                   help="how the --rig maps onto the 21-joint body, if no built-in map fits")
    p.add_argument("--start-from", metavar="FILE", default=None,
                   help="begin every motion with the first pose of this motion file (any "
                        "rig that maps onto the 21-joint body; L2M models)")
    p.add_argument("--keep", metavar="FILE:RANGES", help="keep these seconds of a motion file "
                   "(walk.bvh:0-2s,8-10s; 8- to its end), generate the rest (masked models)")
    p.add_argument("--library", metavar="INDEX", help="compose the motion from the clips of "
                   "this index (motionlang index) that search finds for each part of the "
                   "sentence, instead of a model; the clips are listed in OUTPUT.json")
    add_joint_map_arg(p)   # for --start-from and --keep
    p.set_defaults(func=cmd_generate)

"""``motionlang info | render | convert``: look at, draw and convert one motion file.

Thin layers over :mod:`motionlang.api` and :mod:`motionlang.formats`; every problem is a
:class:`MotionlangError`, which the main entry turns into one line and exit code 2. The
input options (:func:`add_input_args`, :func:`load_input`) serve every command that reads
one motion file.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.analysis.check import printed
from motionlang.api import check, load_rig, read_mapped, render, retarget
from motionlang.cli.options import int_range, output_file, positive_int, rate_float, seconds_float
from motionlang.errors import MotionlangError
from motionlang.formats import info_text, motion_info, write_motion
from motionlang.kinematics import Motion
from motionlang.library.rates import at_export_rate
from motionlang.rendering.output import check_drawable
from motionlang.rendering.scene import RENDER_MAX_FRAMES


def add_input_args(p: argparse.ArgumentParser, many: bool = False) -> None:
    p.add_argument("input", metavar="IN", nargs="+" if many else None,
                   help="motion file: .xml (KIT MMM), .bvh, .amc, .mat (MIT walking data) "
                        "or .txt (DeepMimic)"
                        + ("; or several, and folders (their motion files)" if many else ""))
    p.add_argument("--asf", metavar="PATH", default=None,
                   help="ASF skeleton of an .amc input (default: <subject>.asf next to it)")
    p.add_argument("--source-fps", type=rate_float, default=None, metavar="HZ",
                   help="the take's true frame rate: of an .amc input (default 120), or "
                        "in place of a file's own where its header is wrong")
    p.add_argument("--sequence", type=positive_int, default=None, metavar="N",
                   help="which sequence of a .mat input holding several (1-based; default 1)")
    add_joint_map_arg(p)


def add_joint_map_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--joint-map", metavar="MAP.json", default=None,
                   help="how the input's rig maps onto the 21-joint body, for rigs no "
                        "built-in map recognises (write a template with 'motionlang rig "
                        "template FILE > map.json'; default: chosen by joint names)")


def load_input(args: argparse.Namespace, path: str | None = None) -> Motion:
    """Read ``path`` (default ``args.input``; with ``--asf`` for AMC files, ``--source-fps``
    for AMC files or in place of a file's own rate, ``--sequence`` for MAT files; a ``--joint-map`` is checked against the rig)."""

    path = Path(path or args.input)
    ext = path.suffix.lower()
    if ext != ".amc" and args.asf is not None:
        raise MotionlangError(f"{path}: --asf applies to .amc inputs only")
    if ext != ".mat" and args.sequence is not None:
        raise MotionlangError(f"{path}: --sequence applies to .mat inputs only")
    motion = read_mapped(path, args.joint_map, skeleton=args.asf, sequence=args.sequence or 1,
                         fps=args.source_fps if ext == ".amc" else None)
    if args.source_fps is not None:
        return motion.replace(fps=args.source_fps)
    return at_export_rate(motion, path, joint_map=args.joint_map)


def add_clip_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--start", type=seconds_float, default=None, metavar="S", help="start, seconds")
    p.add_argument("--end", type=seconds_float, default=None, metavar="E", help="end, seconds")


# ------------------------------------------------------------------ info
def cmd_info(args: argparse.Namespace) -> int:

    info = motion_info(load_input(args))
    info["path"] = str(args.input)
    print(json.dumps(info, indent=2) if args.json else info_text(info))
    return 0


# ------------------------------------------------------------------ render
def _add_out(p: argparse.ArgumentParser, what: str) -> None:
    """OUT, given after IN or as ``-o OUT`` (as the other commands take it)."""
    p.add_argument("output", metavar="OUT", type=output_file, nargs="?", help=what)
    p.add_argument("-o", "--output", dest="output_flag", type=output_file, metavar="OUT",
                   help="the same as OUT")


def _output(args: argparse.Namespace) -> str:
    """The one OUT of the command line (:func:`_add_out`)."""
    given = {o for o in (args.output, args.output_flag) if o is not None}
    if not given:
        raise MotionlangError("an output is needed: OUT after the input, or -o OUT")
    if len(given) > 1:
        raise MotionlangError(f"two outputs given ({', '.join(sorted(given))}): give one")
    return given.pop()


def cmd_render(args: argparse.Namespace) -> int:
    args.output = _output(args)
    check_drawable(args.output)   # before the (slow) read
    motion = load_input(args).between(args.start, args.end)
    render(motion, args.output, title=args.title, n_poses=args.strip, fps=args.fps,
           camera=args.camera, trajectory=args.trajectory, max_frames=args.max_frames)
    print(Path(args.output))
    return 0


# ------------------------------------------------------------------ convert
def cmd_convert(args: argparse.Namespace) -> int:
    args.output = _output(args)
    out = Path(args.output)
    if out.resolve() == Path(args.input).resolve():
        raise MotionlangError(f"{out}: output would overwrite the input")
    if args.rig_joint_map and not args.rig:
        raise MotionlangError("--rig-joint-map needs --rig")
    rig = None if args.rig is None else load_rig(args.rig, args.rig_joint_map)  # before reading
    motion = load_input(args).between(args.start, args.end)
    write_motion(motion if rig is None else retarget(motion, rig), out)
    lead = motion.meta.get("reference_frames")
    print(out if not lead else f"{out} (without the input's first {lead} frames: the rig's "
                               "T-pose and the exporter's blend out of it)")
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    if not args.text.strip():
        raise MotionlangError("the sentence to check is empty")
    motion = load_input(args)
    try:
        checks = check(args.text, motion)
    except MotionlangError as exc:   # the analysis' reason, with the file it is about
        raise MotionlangError(f"{args.input}: {exc}") from None
    if not checks:   # nothing was checked: not an answer a script may take for "all met"
        if args.json:
            print("[]")
        raise MotionlangError(printed(args.text, checks))
    print(printed(args.text, checks, as_json=args.json))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "check", help="which actions of a sentence a motion shows, with evidence",
        description="For each action TEXT names: yes (when, evidence), no, or cannot tell, "
                    "from the grounded analysis of the body (motionlang.analysis).")
    p.add_argument("text", metavar="TEXT", help="the sentence, e.g. 'a person sits down'")
    add_input_args(p)
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(func=cmd_check)

    p = subparsers.add_parser("info", help="summary of a motion file",
                              description="Frames, frame rate, duration, joints and DOFs.")
    add_input_args(p)
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(func=cmd_info)

    p = subparsers.add_parser(
        "render", help="draw a motion: animation (.gif/.mp4) or pose strip (.png)",
        description="Render a stick figure. OUT's extension picks the output: .gif or .mp4 "
                    "animation, .png strip of poses (or trajectory with --trajectory).")
    add_input_args(p)
    _add_out(p, "output .gif, .mp4 or .png")
    p.add_argument("--fps", type=rate_float, default=None,
                   help="animation frame rate (default: min(25, source rate))")
    p.add_argument("--max-frames", type=int_range(1, 10**7), default=RENDER_MAX_FRAMES, metavar="N",
                   help="most animation frames to draw: a longer animation is refused")
    add_clip_args(p)
    p.add_argument("--strip", type=int_range(1, 100), default=8, metavar="N",
                   help="number of poses in a .png strip")
    p.add_argument("--trajectory", action="store_true",
                   help="for .png: top view of the root path with footsteps instead of poses")
    p.add_argument("--camera", choices=("auto", "follow", "fixed"), default="auto",
                   help="animation camera (default: follow the body if it travels far)")
    p.add_argument("--title", default=None, help="heading (default: the motion's name)")
    p.set_defaults(func=cmd_render)

    p = subparsers.add_parser(
        "convert", help="convert a motion file (e.g. MMM or AMC to BVH)",
        description="Read IN and write OUT in the format of OUT's extension (.bvh, .glb or "
                    ".gltf for any skeleton; .xml for MMM and .amc for ASF skeletons).")
    add_input_args(p)
    _add_out(p, "output file, e.g. out.bvh")
    add_clip_args(p)
    p.add_argument("--rig", metavar="RIG", help="retarget onto this character's skeleton "
                   "(a BVH file of it) through the 21-joint body; OUT then has its joints")
    p.add_argument("--rig-joint-map", metavar="MAP.json", help="how RIG maps onto the body, "
                   "for rigs no built-in or automatic map fits")
    p.set_defaults(func=cmd_convert)

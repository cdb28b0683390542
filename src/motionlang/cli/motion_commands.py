"""``motionlang info | render | convert``: look at, draw and convert one motion file.

Thin wrappers over :mod:`motionlang.formats` and :mod:`motionlang.rendering`; every problem
is a :class:`MotionlangError`, which the main entry turns into one line and exit code 2.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionlang.cli.options import nonneg_float, output_file, positive_float, positive_int
from motionlang.errors import MotionlangError
from motionlang.kinematics import Motion

RENDER_EXTENSIONS = (".gif", ".mp4", ".png")


def add_input_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", metavar="IN",
                   help="motion file: .xml (KIT MMM), .bvh, .amc or .mat (MIT walking data)")
    p.add_argument("--asf", metavar="PATH", default=None,
                   help="ASF skeleton of an .amc input (default: <subject>.asf next to it)")
    p.add_argument("--source-fps", type=positive_float, default=None, metavar="HZ",
                   help="frame rate of an .amc input (AMC files do not store it; default 120)")
    p.add_argument("--sequence", type=positive_int, default=None, metavar="N",
                   help="which sequence of a .mat input holding several (1-based; default 1)")
    add_joint_map_arg(p)


def add_joint_map_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--joint-map", metavar="MAP.json", default=None,
                   help="how the input's rig maps onto the 21-joint body, for rigs no "
                        "built-in map recognises (write a template with 'motionlang rig "
                        "template FILE > map.json'; default: chosen by joint names)")


def load_input(args: argparse.Namespace) -> Motion:
    """Read ``args.input`` (with ``--asf`` / ``--source-fps`` for AMC files, ``--sequence``
    for MAT files)."""
    from motionlang.formats import read_motion

    path = Path(args.input)
    joint_map = getattr(args, "joint_map", None)
    ext = path.suffix.lower()
    if ext != ".amc" and (args.asf is not None or args.source_fps is not None):
        raise MotionlangError(f"{path}: --asf and --source-fps apply to .amc inputs only")
    if ext != ".mat" and args.sequence is not None:
        raise MotionlangError(f"{path}: --sequence applies to .mat inputs only")
    if ext == ".amc":
        motion = read_motion(path, skeleton=args.asf, fps=args.source_fps, joint_map=joint_map)
    elif ext == ".mat":
        motion = read_motion(path, sequence=1 if args.sequence is None else args.sequence,
                             joint_map=joint_map)
    else:
        motion = read_motion(path, joint_map=joint_map)
    if joint_map is not None:   # a wrong map is named now, whatever the command does next
        from motionlang.api import check_map
        check_map(motion, joint_map)
    return motion


def add_clip_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--start", type=nonneg_float, default=None, metavar="S", help="start, seconds")
    p.add_argument("--end", type=nonneg_float, default=None, metavar="E", help="end, seconds")


def clip_seconds(motion: Motion, start: float | None, end: float | None,
                 where: str) -> Motion:
    """Frames from ``start`` to ``end`` seconds (inclusive of the frame at ``end``)."""
    if start is None and end is None:
        return motion
    a = 0 if start is None else int(round(start * motion.fps))
    b = motion.n_frames - 1 if end is None else int(round(end * motion.fps))
    if a < 0 or (start is not None and start < 0):
        raise MotionlangError(f"{where}: --start must be >= 0 seconds, got {start}")
    if a >= motion.n_frames or b < a:
        raise MotionlangError(f"{where}: no frames between {start or 0:g} s and "
                              f"{'the end' if end is None else f'{end:g} s'} (motion lasts "
                              f"{motion.duration:.2f} s)")
    return motion[a:b + 1]


# ------------------------------------------------------------------ info
def cmd_info(args: argparse.Namespace) -> int:
    from motionlang.formats import motion_info

    info = motion_info(load_input(args))
    info["path"] = str(args.input)
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    names = info["joint_names"]
    shown = ", ".join(names[:8]) + (f", ... ({len(names)} in all)" if len(names) > 8 else "")
    print(f"{info['path']}")
    print(f"  format    {info['source_format']}  (skeleton {info.get('skeleton', '?')})")
    print(f"  frames    {info['frames']} at {info['fps']:g} Hz = {info['duration_s']:.2f} s")
    print(f"  joints    {info['joints']} with {info['dofs']} DOFs (+ root), "
          f"{info['nodes']} skeleton nodes")
    print(f"  body      {info['stature_m']:.2f} m tall; lengths in {info['unit']}")
    print(f"  names     {shown}")
    return 0


# ------------------------------------------------------------------ render
def cmd_render(args: argparse.Namespace) -> int:
    from motionlang.rendering import plot_trajectory, render_animation, render_strip

    out = Path(args.output)
    ext = out.suffix.lower()
    if ext not in RENDER_EXTENSIONS:  # checked before the (slow) read
        raise MotionlangError(f"{out}: cannot render to {ext or '(no extension)'!r}; use "
                              f"{', '.join(RENDER_EXTENSIONS)}")
    motion = clip_seconds(load_input(args), args.start, args.end, str(args.input))
    title = args.title if args.title is not None else motion.name
    if ext == ".png" and args.trajectory:
        plot_trajectory(motion, out, title=title)
    elif ext == ".png":
        render_strip(motion, out, n_frames=args.strip or 8, title=title)
    else:
        render_animation(motion, out, fps=args.fps, title=title, camera=args.camera)
    print(out)
    return 0


# ------------------------------------------------------------------ convert
def cmd_convert(args: argparse.Namespace) -> int:
    from motionlang.formats import write_motion

    out = Path(args.output)
    if out.resolve() == Path(args.input).resolve():
        raise MotionlangError(f"{out}: output would overwrite the input")
    motion = clip_seconds(load_input(args), args.start, args.end, str(args.input))
    write_motion(motion, out)
    print(out)
    return 0


def register(subparsers) -> None:
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
    p.add_argument("output", metavar="OUT", type=output_file, help="output .gif, .mp4 or .png")
    p.add_argument("--fps", type=positive_float, default=None,
                   help="animation frame rate (default: min(25, source rate))")
    add_clip_args(p)
    p.add_argument("--strip", type=positive_int, default=None, metavar="N",
                   help="number of poses in a .png strip (default 8)")
    p.add_argument("--trajectory", action="store_true",
                   help="for .png: top view of the root path with footsteps instead of poses")
    p.add_argument("--camera", choices=("auto", "follow", "fixed"), default="auto",
                   help="animation camera (default: follow the body if it travels far)")
    p.add_argument("--title", default=None, help="heading (default: the motion's name)")
    p.set_defaults(func=cmd_render)

    p = subparsers.add_parser(
        "convert", help="convert a motion file (e.g. MMM or AMC to BVH)",
        description="Read IN and write OUT in the format of OUT's extension (.bvh for any "
                    "skeleton; .xml for MMM and .amc for ASF skeletons).")
    add_input_args(p)
    p.add_argument("output", metavar="OUT", type=output_file, help="output file, e.g. out.bvh")
    add_clip_args(p)
    p.set_defaults(func=cmd_convert)

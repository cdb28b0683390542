"""``motionlang rig show | template``: how a motion file's rig maps onto the 21-joint body.

``rig show FILE`` prints the rig's joints, the joint map chosen (a built-in one from the
joint names, or ``--joint-map MAP``) and where each of the 21 body joints comes from.
``rig template FILE > map.json`` writes a map to fill in for a rig no built-in map fits
(``features.joint_map.template_map``); pass it back with ``--joint-map map.json``.
"""
from __future__ import annotations

import argparse
import json
import re
import textwrap

from motionlang.cli.motion_commands import add_input_args, load_input


def _spec_text(spec) -> str:
    if isinstance(spec, str):
        return spec
    args = ", ".join(str(a) if isinstance(a, str) else f"{a:g}" for a in spec[1:])
    return f"{spec[0]}({args})"


def _rig_match(args: argparse.Namespace):
    from motionlang.features.joint_map import match_rig

    motion = load_input(args)
    joint_map = getattr(args, "joint_map", None) or motion.meta.get("joint_map")
    return motion, match_rig(motion.skeleton, joint_map=joint_map)


def cmd_show(args: argparse.Namespace) -> int:
    from motionlang.features.joint_map import KIT21_NAMES

    motion, m = _rig_match(args)
    names = list(motion.skeleton.names)
    ends = [n for n in names if re.search(r"_end\d*$", n, re.IGNORECASE)]
    joints = [n for n in names if n not in ends]
    body = {k: m.sources[k] for k in KIT21_NAMES}
    used = {n for s in body.values() for n in ([s] if isinstance(s, str) else s[1:3])}
    if args.json:
        print(json.dumps({"path": str(args.input), "rig": motion.skeleton.name,
                          "joints": joints, "end_sites": len(ends), "map": m.name,
                          "about": m.about, "body": body}, indent=2))
        return 0
    wrap = textwrap.TextWrapper(width=92, initial_indent=" " * 11, subsequent_indent=" " * 11)
    print(f"{args.input}")
    print(f"  rig      {motion.skeleton.name}: {len(joints)} joints"
          + (f" (+ {len(ends)} end sites)" if ends else ""))
    print(wrap.fill(", ".join(joints)))
    print(f"  map      {m.name}: {m.about}")
    print("  body joint <- rig joint")
    for k in KIT21_NAMES:
        print(f"    {k:<6} <- {_spec_text(body[k])}")
    unused = [n for n in joints if n not in used]
    if unused:
        print("  unused   " + wrap.fill(", ".join(unused)).lstrip())
    return 0


def dump_map(d: dict) -> str:
    """A joint map as JSON with one line per body joint (``json.dumps`` would spread every
    ``["mid", a, b]`` over four lines)."""
    lines = []
    for key, value in d.items():
        if isinstance(value, dict):
            inner = [f"    {json.dumps(k)}: {json.dumps(v)}" for k, v in value.items()]
            lines.append(f"  {json.dumps(key)}: {{\n" + ",\n".join(inner) + "\n  }")
        else:
            lines.append(f"  {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}"


def cmd_template(args: argparse.Namespace) -> int:
    from motionlang.features.joint_map import template_map

    print(dump_map(template_map(load_input(args).skeleton)))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("rig", help="how a file's rig maps onto the 21-joint body",
                              description="Show the joint map chosen for a motion file's "
                                          "rig, or write a map template to fill in.")
    sub = p.add_subparsers(dest="rig_command", metavar="ACTION")
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])

    s = sub.add_parser("show", help="the rig's joints, its map, each body joint's source")
    add_input_args(s)   # with --joint-map: show how a map of yours applies
    s.add_argument("--json", action="store_true", help="print JSON instead of text")
    s.set_defaults(func=cmd_show)

    t = sub.add_parser("template", help="print a JSON joint map to fill in for this rig",
                       description="Print a joint map for the rig: the closest built-in "
                                   "map's guesses, \"\" where none, and the rig's joints. "
                                   "Use: motionlang rig template FILE > map.json")
    add_input_args(t)
    t.set_defaults(func=cmd_template)

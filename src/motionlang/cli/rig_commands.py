"""``motionlang rig show | template``: how a motion file's rig maps onto the 21-joint body.

``rig show FILE`` prints the rig's joints, the joint map chosen (a built-in one from the
joint names, the automatic one of ``features.rig_auto``, or ``--joint-map MAP``), where each of
the 21 body joints comes from, how it was found and with what confidence
(``features.joint_map.rig_summary``). ``rig template FILE > map.json`` writes a map to fill
in for a rig no built-in map fits (``features.joint_map.template_map``); pass it back with
``--joint-map map.json``.
"""
from __future__ import annotations

import argparse
import json

from motionlang.cli.motion_commands import add_input_args, load_input
from motionlang.features.joint_map import map_json, rig_summary, summary_text, template_map


def cmd_show(args: argparse.Namespace) -> int:

    motion = load_input(args)
    s = rig_summary(motion.skeleton, motion.meta.get("joint_map"))
    print(json.dumps({"path": str(args.input), **s}, indent=2) if args.json else
          f"{args.input}\n{summary_text(s)}")
    return 0


def cmd_template(args: argparse.Namespace) -> int:

    print(map_json(template_map(load_input(args).skeleton)))
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

"""``motionlang index DIR -o FILE`` and ``motionlang search QUERY --index FILE``: a folder of
motion files searchable by text, thin over ``ml.index`` and ``ml.search`` (``library/``)."""
from __future__ import annotations

import argparse
import json
import sys

from motionlang.api import index, search
from motionlang.cli.config_options import add_config_options, config_from_args, config_values
from motionlang.cli.options import output_file
from motionlang.library.merge import merge_indexes
from motionlang.library.options import IndexOptions, SearchOptions  # torch-free
from motionlang.library.search import nothing_found


def cmd_index(args: argparse.Namespace) -> int:
    summary = index(args.dir, args.output, args.model,
                    **config_values(config_from_args(IndexOptions, args)))
    for path, why in summary.failed:
        print(f"skipped {path}: {why}", file=sys.stderr)
    print(json.dumps(summary.as_dict(), indent=1) if args.json else summary.text())
    return 0


def cmd_search(args: argparse.Namespace) -> int:
    opts = config_values(config_from_args(SearchOptions, args))
    hits = search(args.query, args.index, model=args.model, render=args.render, **opts)
    if not hits and not args.json:
        print(nothing_found(args.index, opts))
        return 0
    print(json.dumps([h._asdict() for h in hits], indent=1) if args.json else
          "\n".join(h.line(i) for i, h in enumerate(hits, 1)))
    return 0


def cmd_merge(args: argparse.Namespace) -> int:
    d = merge_indexes(args.shards, args.output, root=args.root)
    print(f"{args.output}: {len(d.entries)} takes, {len(d.vectors)} windows from "
          f"{len(args.shards)} shards" + (f" (still only shards {d.shard})" if d.shard else ""))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "index", help="make a folder of motion files searchable by text",
        description="Cut every motion file under DIR (recursively; .bvh, .amc + .asf, .xml "
                    "MMM, .mat, DeepMimic .txt; any rig) into overlapping windows and embed "
                    "each; run it again to embed only new or changed files. Files that do not "
                    "read are listed with their reason and skipped.")
    p.add_argument("dir", metavar="DIR", help="the folder of motion files")
    p.add_argument("-o", "--output", required=True, type=output_file, metavar="FILE",
                   help="the index file (made, or brought up to date)")
    add_config_options(p, IndexOptions)
    h = ("the takes and spans of an index (motionlang index) that best match a sentence, the "
         "overlapping windows of a take merged into one span")
    s = subparsers.add_parser("search", help=h, description=h[0].upper() + h[1:] + ".")
    s.add_argument("query", metavar="QUERY", help='what to find, e.g. "someone waves"')
    s.add_argument("--index", required=True, metavar="FILE", help="the index file")
    add_config_options(s, SearchOptions)
    s.add_argument("--render", type=output_file, metavar="PNG",
                   help="also write a contact sheet of the hits' poses (.png)")
    for q, default in ((p, "the packaged retrieval model, where installed"),
                       (s, "the one the index was made with")):
        q.add_argument("--model", help="a model that puts sentences and motions in one space "
                                       f"(packaged name, checkpoint or run folder; default: "
                                       f"{default})")
        q.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=cmd_index)
    s.set_defaults(func=cmd_search)
    m = subparsers.add_parser("merge-index", help="join index shards (index --shard K/N) "
                              "into one index")
    m.add_argument("shards", nargs="+", metavar="SHARD", help="the shards' index files")
    m.add_argument("-o", "--output", required=True, type=output_file, metavar="FILE",
                   help="the joined index file")
    m.add_argument("--root", help="where the indexed folder is, if the shards name other "
                                  "places (made on other machines)")
    m.set_defaults(func=cmd_merge)

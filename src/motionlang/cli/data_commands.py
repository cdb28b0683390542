"""``motionlang data ...``: download KIT-ML, summarise a dataset folder, write splits.

    motionlang data download kitml --dest DIR [--url URL] [--sha256 HEX]
    motionlang data info DIR [--max-seconds 30] [--json]
    motionlang data split DIR --fractions 0.8 0.1 0.1 --seed 0 --out DIR

``DIR`` is an extracted KIT-ML release (or a folder above it) or a custom dataset folder
with ``captions.csv`` / ``captions.jsonl``.
"""
from __future__ import annotations

import argparse
import importlib
import json
from pathlib import Path

from motionlang.errors import DatasetError


def _is_custom(folder: Path) -> bool:
    from motionlang.datasets.custom import CAPTION_NAMES
    return any((folder / n).is_file() for n in CAPTION_NAMES)


def _records(folder: Path, max_seconds: float | None) -> list:
    """Records of either dataset kind (custom datasets have no duration filter)."""
    if _is_custom(folder):
        from motionlang.datasets.custom import load_custom
        return load_custom(folder)
    from motionlang.datasets.kitml import load_kitml
    return load_kitml(folder, max_seconds=max_seconds)


def cmd_download(args: argparse.Namespace) -> int:
    from motionlang.datasets.kitml import KITML_URL, download_kitml
    if args.dataset != "kitml":  # argparse choices guard this; kept for API callers
        raise DatasetError(f"unknown dataset {args.dataset!r}")
    root = download_kitml(args.dest, url=args.url or KITML_URL, sha256=args.sha256,
                          include_raw=args.include_raw, keep_archive=not args.remove_archive)
    print(root)
    return 0


def _custom_summary(folder: Path) -> dict:
    recs = _records(folder, None)
    return {"root": str(folder), "kind": "custom", "motions": len(recs),
            "annotations": sum(len(r.annotations) for r in recs),
            "without_annotations": sum(not r.has_annotations for r in recs)}


def cmd_info(args: argparse.Namespace) -> int:
    folder = Path(args.dir)
    if _is_custom(folder):
        info = _custom_summary(folder)
    else:
        from motionlang.datasets.kitml import kitml_summary
        info = {"kind": "kitml", **kitml_summary(folder, max_seconds=args.max_seconds)}
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"{info['kind']} dataset at {info['root']}")
    if info["kind"] == "custom":
        print(f"  motions {info['motions']}, annotations {info['annotations']}, "
              f"without annotations {info['without_annotations']}")
        return 0
    for part, title in (("all", "all motions"), ("kept", f"< {info['max_seconds']:g} s")):
        s = info[part]
        d = s["duration_s"]
        dur = "" if d["min"] is None else (f", duration min/median/max "
                                           f"{d['min']:.2f}/{d['median']:.2f}/{d['max']:.2f} s")
        print(f"  {title:>12}: motions {s['motions']}, annotations {s['annotations']}, "
              f"without annotations {s['without_annotations']}, {s['hours']:.2f} h{dur}")
    return 0


def cmd_split(args: argparse.Namespace) -> int:
    from motionlang.datasets.splits import random_split, save_splits
    recs = _records(Path(args.dir), args.max_seconds)
    if not recs:
        raise DatasetError(f"{args.dir}: no motions to split")
    splits = random_split([r.id for r in recs], args.fractions, seed=args.seed)
    for path in save_splits(splits, args.out):
        print(f"{path}: {sum(1 for _ in path.open())} ids")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("data", help="download, inspect and split datasets",
                              description="Download KIT-ML, summarise a dataset folder, write splits.")
    sub = p.add_subparsers(dest="data_command", metavar="DATA_COMMAND")
    p.set_defaults(func=lambda args: (p.print_help(), 1)[1])

    d = sub.add_parser("download", help="download and extract a dataset release")
    d.add_argument("dataset", choices=["kitml"])
    d.add_argument("--dest", required=True, help="folder for the archive and extracted data")
    d.add_argument("--url", help="override the release URL (default: KIT's 2016-10-10 zip)")
    d.add_argument("--sha256", help="expected sha256 of the archive (KIT publishes none)")
    d.add_argument("--include-raw", action="store_true", help="also extract *_raw.c3d files")
    d.add_argument("--remove-archive", action="store_true",
                   help="delete the zip after extraction")
    d.set_defaults(func=cmd_download)

    i = sub.add_parser("info", help="counts and durations of a dataset folder")
    i.add_argument("dir")
    i.add_argument("--max-seconds", type=float, default=30.0,
                   help="duration filter for the 'kept' counts (default 30)")
    i.add_argument("--json", action="store_true", help="print JSON")
    i.set_defaults(func=cmd_info)

    s = sub.add_parser("split", help="write a seeded random train/val/test split")
    s.add_argument("dir")
    s.add_argument("--fractions", type=float, nargs="+", default=[0.8, 0.1, 0.1],
                   help="2 (train test) or 3 (train val test) fractions summing to 1")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--max-seconds", type=float, default=30.0,
                   help="KIT-ML: split only motions shorter than this")
    s.add_argument("--out", required=True, help="folder for train.txt, val.txt, test.txt")
    s.set_defaults(func=cmd_split)

    try:  # the corpus team's ``data synth`` lives in its own module
        synth = importlib.import_module("motionlang.cli.synth_commands")
    except ModuleNotFoundError as exc:
        if exc.name != "motionlang.cli.synth_commands":
            raise
    else:
        synth.register_synth(sub)

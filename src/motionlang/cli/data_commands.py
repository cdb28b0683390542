"""``motionlang data ...``: download KIT-ML, summarise a dataset folder, write splits.

    motionlang data download kitml --dest DIR [--url URL] [--sha256 HEX]
    motionlang data info DIR [--max-seconds 30] [--json]
    motionlang data split DIR --fractions 0.8 0.1 0.1 --seed 0 --out DIR
    motionlang data export-h3d --data DATA --out DIR [--body kit|smpl] [--mirror]

``DIR`` is an extracted KIT-ML release (or a folder above it) or a custom dataset folder
with ``captions.csv`` / ``captions.jsonl``. ``DATA`` is anything training reads (such a
folder, ``humanml3d:DIR`` or ``kitml-h3d:DIR``).
"""
from __future__ import annotations

import argparse
import json

from motionlang.cli.options import nonneg_float, output_dir, positive_float, positive_int, seed_int
from motionlang.cli.synth_commands import register_synth
from motionlang.datasets.folders import folder_summary, split_folder, summary_text
from motionlang.datasets.humanml3d_export import export_h3d
from motionlang.datasets.kitml import KITML_URL, download_kitml
from motionlang.datasets.seq2seq_pairs import load_records
from motionlang.utils.folder_lock import check_new_output, check_no_clash
from motionlang.utils.progress import progress


def cmd_download(args: argparse.Namespace) -> int:
    root = download_kitml(args.dest, url=args.url or KITML_URL, sha256=args.sha256,
                          include_raw=args.include_raw, keep_archive=not args.remove_archive)
    print(root)
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    info = folder_summary(args.dir, args.max_seconds)
    print(json.dumps(info, indent=2) if args.json else summary_text(info))
    return 0


def cmd_split(args: argparse.Namespace) -> int:
    if not args.overwrite:
        names = ("train", "val", "test") if len(args.fractions) == 3 else ("train", "test")
        check_no_clash(args.out, {f"{n}.txt" for n in names}, "--out")
    written = split_folder(args.dir, args.out, args.fractions, seed=args.seed,
                           max_seconds=args.max_seconds)
    for path, n in written.items():
        print(f"{path}: {n} ids")
    return 0


def cmd_export_h3d(args: argparse.Namespace) -> int:
    import os
    import time

    check_new_output(args.out, "--out", "an export goes into a new or empty folder")
    t0 = time.perf_counter()
    records = load_records(args.data, args.max_seconds, args.joint_map)
    print(f"export-h3d: {len(records)} motions from {args.data} "
          f"({time.perf_counter() - t0:.1f} s to list)", flush=True)

    # a bar on a terminal, else a line every 30 s
    bar = progress(total=len(records), desc="export-h3d", unit="motions")

    def report(done: int, total: int, _id: str) -> None:
        bar.update(done - bar.n)

    workers = args.workers or max(1, min(2, os.cpu_count() or 1))
    with bar:
        info = export_h3d(records, args.out, args.body, mirror=args.mirror,
                          heading=args.heading, seed=args.seed, workers=workers,
                          on_progress=report)
    mirrored = f" (+{info['motions']} mirrored)" if info["mirrored"] else ""
    skipped = f"; skipped {len(info['skipped'])} too short" if info["skipped"] else ""
    print(f"wrote {info['motions']} motions{mirrored} to {args.out}: {info['body']} body, "
          f"{info['vector_dim']} numbers a row at {info['fps']:g} fps{skipped}")
    return 0


def _register_export_h3d(sub) -> None:
    e = sub.add_parser("export-h3d", help="write a dataset in the HumanML3D layout",
                       description="Write new_joint_vecs/, new_joints/, texts/, Mean.npy, "
                                   "Std.npy and train/val/test.txt (HumanML3D layout) for "
                                   "every motion of a dataset; the folder appears only once "
                                   "complete.")
    e.add_argument("--data", required=True,
                   help="dataset folder, humanml3d:DIR or kitml-h3d:DIR")
    e.add_argument("--out", required=True, type=output_dir, help="new output folder")
    e.add_argument("--body", choices=["kit", "smpl"], default="kit",
                   help="kit: the 21-joint body of any rig, 12.5 fps, mm (default); smpl: the "
                        "22 SMPL joints of an SMPL-named rig, 20 fps, m")
    e.add_argument("--mirror", action="store_true",
                   help="also write mirrored copies M<ID> (captions' left/right swapped)")
    e.add_argument("--heading", choices=["public", "body"], default="public",
                   help="per-frame heading: as the public code computes it (default) or the "
                        "unsmoothed hips + shoulders")
    e.add_argument("--seed", type=seed_int, default=0, help="seed of the train/val/test split")
    e.add_argument("--max-seconds", type=positive_float, default=None,
                   help="skip motions longer than this (default: keep all)")
    e.add_argument("--joint-map", help="JSON joint map for a custom folder's rig")
    e.add_argument("--workers", type=positive_int, default=None,
                   help="processes converting motions (default: min(2, CPUs))")
    e.set_defaults(func=cmd_export_h3d)


def register(subparsers) -> None:
    p = subparsers.add_parser("data", help="download, inspect and split datasets",
                              description="Download KIT-ML, summarise a dataset folder, write splits.")
    sub = p.add_subparsers(dest="data_command", metavar="DATA_COMMAND")
    p.set_defaults(func=lambda args: (p.print_help(), 1)[1])

    d = sub.add_parser("download", help="download and extract a dataset release")
    d.add_argument("dataset", choices=["kitml"], help="the dataset to fetch")
    d.add_argument("--dest", required=True, type=output_dir,
                   help="folder for the archive and extracted data")
    d.add_argument("--url", help="override the release URL (default: KIT's 2016-10-10 zip)")
    d.add_argument("--sha256", help="expected sha256 of the archive (KIT publishes none)")
    d.add_argument("--include-raw", action="store_true", help="also extract *_raw.c3d files")
    d.add_argument("--remove-archive", action="store_true",
                   help="delete the zip after extraction")
    d.set_defaults(func=cmd_download)

    i = sub.add_parser("info", help="counts and durations of a dataset folder")
    i.add_argument("dir", help="a KIT-ML-format or custom dataset folder")
    i.add_argument("--max-seconds", type=positive_float, default=30.0,
                   help="duration filter for the 'kept' counts")
    i.add_argument("--json", action="store_true", help="print JSON")
    i.set_defaults(func=cmd_info)

    s = sub.add_parser("split", help="write a seeded random train/val/test split")
    s.add_argument("dir", help="a KIT-ML-format or custom dataset folder")
    s.add_argument("--fractions", type=nonneg_float, nargs="+", default=[0.8, 0.1, 0.1],
                   help="2 (train test) or 3 (train val test) fractions summing to 1")
    s.add_argument("--seed", type=seed_int, default=0, help="seed of the random split")
    s.add_argument("--max-seconds", type=positive_float, default=30.0,
                   help="KIT-ML: split only motions shorter than this")
    s.add_argument("--out", required=True, type=output_dir,
                   help="folder for train.txt, val.txt, test.txt")
    s.add_argument("--overwrite", action="store_true",
                   help="replace split files already in --out (default: refused)")
    s.set_defaults(func=cmd_split)

    _register_export_h3d(sub)
    register_synth(sub)

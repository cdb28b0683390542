"""``motionlang data synth``: write the procedural motion-language corpus."""
from __future__ import annotations

import time

from motionlang.cli.options import nonneg_int, output_dir, positive_int, seed_int
from motionlang.datasets.synth.corpus import write_corpus
from motionlang.utils.folder_lock import check_new_output, check_no_clash


def register_synth(data_subparsers) -> None:
    """Add ``synth`` to the ``motionlang data`` subcommands."""
    p = data_subparsers.add_parser(
        "synth", help="generate the synthetic KIT-style motion-language corpus",
        description="Write N synthetic motions with 2-4 sentences and ground truth each, in "
                    "the KIT-ML release layout (NNNNN_mmm.xml, _annotations.json, _meta.json). "
                    "The same seed gives byte-identical files.")
    p.add_argument("--out", required=True, type=output_dir, help="output folder")
    p.add_argument("--n", type=positive_int, default=1000, help="number of motions (default 1000)")
    p.add_argument("--seed", type=seed_int, default=0, help="corpus seed (default 0)")
    p.add_argument("--start", type=nonneg_int, default=0,
                   help="index of the first sample (to extend a corpus; default 0)")
    p.add_argument("--workers", type=positive_int, default=None,
                   help="worker processes (default: min(2, CPUs))")
    p.add_argument("--overwrite", action="store_true",
                   help="write into a folder that holds files already, replacing the samples "
                        "of the same ids (default: a non-empty --out is refused, and with "
                        "--start only the files of the new ids must be absent)")
    p.set_defaults(func=_run)


def _run(args) -> int:

    if not args.overwrite:   # an existing dataset is never overwritten unasked
        if args.start:
            check_no_clash(args.out, {f"{i + 1:05d}_{part}"
                                      for i in range(args.start, args.start + args.n)
                                      for part in ("mmm.xml", "annotations.json",
                                                   "meta.json")}, "--out")
        else:
            check_new_output(args.out, "--out", "give --overwrite to write over it, "
                                                "--start N to extend it, or another folder")
    t0 = time.perf_counter()
    ids = write_corpus(args.out, args.n, args.seed, start=args.start, workers=args.workers)
    print(f"wrote {len(ids)} motions ({ids[0]}..{ids[-1]}) to {args.out} "
          f"in {time.perf_counter() - t0:.1f} s")
    return 0

"""A procedural corpus restricted to motions made of given primitives only, as links to the
original files (nothing copied), for focused experiments such as "does the L2M learn to
walk backwards when that is one of two things it sees?".

    .venv/bin/python scripts/corpus_subset.py corpus walkfb --only walk/forward walk/backward stand

A motion is kept when each of its primitives is in ``--only`` (labels as
``datasets.seq2seq_pairs.primitive_labels`` writes them: "action/direction" or "action") and
at least one is not "stand". Prints how many motions have each label.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
from pathlib import Path

SUFFIXES = ("_meta.json", "_mmm.xml", "_annotations.json")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source", type=Path, help="procedural corpus (motionlang data synth)")
    ap.add_argument("out", type=Path, help="new folder (must not exist)")
    ap.add_argument("--only", nargs="+", required=True, metavar="LABEL")
    args = ap.parse_args(argv)
    from motionlang.datasets.seq2seq_pairs import primitive_labels
    if args.out.exists():
        raise SystemExit(f"{args.out}: already exists")
    metas = sorted(args.source.glob("*_meta.json"))
    if not metas:
        raise SystemExit(f"{args.source}: no *_meta.json (not a procedural corpus)")
    allowed, kept, counts = set(args.only), [], collections.Counter()
    for meta in metas:
        labels = primitive_labels(json.loads(meta.read_text()))
        if labels and set(labels) <= allowed and set(labels) != {"stand"}:
            kept.append(meta)
            counts.update(set(labels))
    if not kept:
        raise SystemExit(f"{args.source}: no motion made only of {', '.join(args.only)}")
    tmp = args.out.with_name(args.out.name + ".partial")
    if tmp.exists():
        raise SystemExit(f"{tmp}: left by an interrupted run; remove it first")
    tmp.mkdir(parents=True)
    for meta in kept:
        stem = meta.name[:-len("_meta.json")]
        for suffix in SUFFIXES:
            src = (meta.parent / (stem + suffix)).resolve()
            if src.exists():
                os.symlink(src, tmp / src.name)
    tmp.rename(args.out)   # the folder appears whole or not at all
    print(f"{args.out}: {len(kept)} of {len(metas)} motions; " +
          ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

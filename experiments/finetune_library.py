"""Learn from your own library: the packaged retrieval model fine-tuned on a library captioned
by the grounded analysis alone (``train retrieval --data analysis:DIR --init retrieval``),
scored on held-out files of that library with words nobody trained on.

    OMP_NUM_THREADS=2 .venv/bin/python experiments/finetune_library.py \\
        --library /tmp/cmu_dev/cmu-dev --trials ../shared/data/cmu_dev/trials.tsv \\
        --work /tmp/ft [--epochs 10] [--lr 1e-4]
    OMP_NUM_THREADS=2 .venv/bin/python experiments/finetune_library.py \
        --bandai /tmp/bandai --init RUN_WITHOUT_BANDAI --work /tmp/ftb

The library's takes are halved by the hash of their file's stem (every rig copy of a trial on
the same side): one half, as a folder of links, is the training library; the other is held
out. The held-out takes are scored with CMU's own descriptions (``trials.tsv``), never
trained on: each distinct description of a held-out trial ranks the held-out takes, a hit
being a take whose trial has that description. Text -> motion R@1 / R@5 / median rank of
the packaged model and of the fine-tuned one, on the same queries and takes.

With ``--bandai DIR`` (the extracted Bandai Namco archives) the library is theirs, treated as
uncaptioned: the training library is every take outside Bandai's test split, captioned by
the analysis alone; the held-out takes are the test split, scored with the sentences the
Bandai grammar writes from their labels (the labels used only to score), a hit being a take
of the query's action. The packaged model was trained on Bandai's captions, so the start
is a model that never saw them (``--init``, e.g. one trained on the procedural corpus).
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

import motionlang as ml
from motionlang.evaluation.metrics.t2m import retrieval_scores
from motionlang.formats import is_motion_file


def half(stem: str) -> int:
    return int(hashlib.sha256(stem.encode()).hexdigest()[:8], 16) % 2


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--library", help="a folder of takes (with --trials)")
    ap.add_argument("--trials", help="CMU's descriptions of the library's trials")
    ap.add_argument("--bandai", help="the Bandai archives' folder, instead of --library")
    ap.add_argument("--init", default="retrieval", help="the model fine-tuned (and scored as "
                                                        "the baseline)")
    ap.add_argument("--work", required=True, help="a folder for the links and the run")
    ap.add_argument("--epochs", type=int, default=10)
    ap.add_argument("--lr", type=float, default=1e-4)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    if (args.bandai is None) == (args.library is None) or \
            (args.library is not None and args.trials is None):
        ap.error("give --library with --trials, or --bandai")
    work = Path(args.work)
    if args.bandai:
        train_dir, held, queries, hits = bandai_halves(Path(args.bandai), work)
    else:
        train_dir, held, queries, hits = cmu_halves(Path(args.library), Path(args.trials),
                                                    work)
    run = work / "run"
    if not (run / "model.pt").exists():
        subprocess.run([sys.executable, "-m", "motionlang.cli.main", "train", "retrieval",
                        "--data", f"analysis:{train_dir}", "--init", args.init,
                        "--out", str(run), "--epochs", str(args.epochs), "--lr", str(args.lr),
                        "--threads", str(args.threads), "--overwrite"], check=True)
    print(f"held out {len(held)} takes, {len(queries)} distinct queries")
    for name in (args.init, str(run / "model.pt")):
        model = ml.load_model(name, kind="retrieval")
        motions = model.embed_motions([model.motion_rows(ml.read_motion(p)) for p in held])
        sims = model.embed_texts(queries) @ motions.T
        r = retrieval_scores(sims, hits)
        print(f"{'fine-tuned' if name != args.init else name}: text -> motion "
              f"R@1 {r['t2m/R01']:.1f} %, R@5 {r['t2m/R05']:.1f} %, MedR {r['t2m/MedR']:g}")
    return 0


def _link(path: Path, root: Path, into: Path) -> None:
    link = into / path.relative_to(root)
    link.parent.mkdir(parents=True, exist_ok=True)
    if not link.exists():
        os.symlink(path.resolve(), link)


def bandai_halves(root: Path, work: Path):
    """Training folder (links to the takes outside the test split), held-out test takes,
    the label sentences of the test takes as queries, (queries, takes) hits by action."""
    from motionlang.datasets.bandai import load_bandai_text
    train_dir = work / "train"
    held, content = [], []
    sentence_of: dict[str, str] = {}
    for r in load_bandai_text(root, per_take=1):
        if r.split != "test":
            _link(r.path, root, train_dir)
            continue
        held.append(r.path)
        content.append(r.content)
        sentence_of.setdefault(r.annotations[0], r.content)
    queries = sorted(sentence_of)
    hits = np.array([[sentence_of[q] == c for c in content] for q in queries])
    print(f"training library: {sum(1 for _ in train_dir.rglob('*.bvh'))} takes")
    return train_dir, held, queries, hits


def cmu_halves(lib: Path, trials: Path, work: Path):
    """The CMU library halved by stem (module docstring): training folder, held-out takes,
    CMU's descriptions as queries, (queries, takes) hits."""
    with open(trials, newline="") as fh:
        described = {r["trial"]: r["cmu_description"] for r in csv.DictReader(fh, delimiter="\t")}
    files = [p for p in sorted(lib.rglob("*")) if p.is_file() and is_motion_file(p)]
    train_dir = work / "train"
    held = []
    for p in files:
        if half(p.stem) == 0:
            _link(p, lib, train_dir)
        elif p.stem in described:
            held.append(p)
    queries = sorted({described[p.stem] for p in held})
    hits = np.array([[described[p.stem] == q for p in held] for q in queries])
    print(f"{len(files)} files; training half {sum(half(p.stem) == 0 for p in files)} files; "
          f"held out {len(held)} takes of {len({p.stem for p in held})} trials")
    return train_dir, held, queries, hits


if __name__ == "__main__":
    sys.exit(main())

"""Learn from your own library: the packaged retrieval model fine-tuned on a library captioned
by the grounded analysis alone (``train retrieval --data analysis:DIR --init retrieval``),
scored on held-out files of that library with words nobody trained on.

    OMP_NUM_THREADS=2 .venv/bin/python experiments/finetune_library.py \\
        --library /tmp/cmu_dev/cmu-dev --trials ../shared/data/cmu_dev/trials.tsv \\
        --work /tmp/ft [--epochs 10] [--lr 1e-4]

The library's takes are halved by the hash of their file's stem (every rig copy of a trial on
the same side): one half, as a folder of links, is the training library; the other is held
out. The held-out takes are scored with CMU's own descriptions (``trials.tsv``), never
trained on: each distinct description of a held-out trial ranks the held-out takes, a hit
being a take whose trial has that description. Text -> motion R@1 / R@5 / median rank of
the packaged model and of the fine-tuned one, on the same queries and takes.
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
    ap.add_argument("--library", required=True)
    ap.add_argument("--trials", required=True)
    ap.add_argument("--work", required=True, help="a folder for the links and the run")
    ap.add_argument("--epochs", type=int, default=10)
    ap.add_argument("--lr", type=float, default=1e-4)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    lib, work = Path(args.library), Path(args.work)
    with open(args.trials, newline="") as fh:
        described = {r["trial"]: r["cmu_description"] for r in csv.DictReader(fh, delimiter="\t")}
    files = [p for p in sorted(lib.rglob("*")) if p.is_file() and is_motion_file(p)]
    train_dir = work / "train"
    held = []
    for p in files:
        if half(p.stem) == 0:
            link = train_dir / p.relative_to(lib)
            link.parent.mkdir(parents=True, exist_ok=True)
            if not link.exists():
                os.symlink(p.resolve(), link)
        elif p.stem in described:
            held.append(p)
    run = work / "run"
    if not (run / "model.pt").exists():
        subprocess.run([sys.executable, "-m", "motionlang.cli.main", "train", "retrieval",
                        "--data", f"analysis:{train_dir}", "--init", "retrieval",
                        "--out", str(run), "--epochs", str(args.epochs), "--lr", str(args.lr),
                        "--threads", str(args.threads), "--overwrite"], check=True)
    queries = sorted({described[p.stem] for p in held})
    hits = np.array([[described[p.stem] == q for p in held] for q in queries])
    print(f"{len(files)} files; training half {sum(half(p.stem) == 0 for p in files)} files; "
          f"held out {len(held)} takes of {len({p.stem for p in held})} trials, "
          f"{len(queries)} distinct descriptions as queries")
    for name in ("retrieval", str(run / "model.pt")):
        model = ml.load_model(name, kind="retrieval")
        motions = model.embed_motions([model.motion_rows(ml.read_motion(p)) for p in held])
        sims = model.embed_texts(queries) @ motions.T
        r = retrieval_scores(sims, hits)
        print(f"{'packaged' if name == 'retrieval' else 'fine-tuned'}: text -> motion "
              f"R@1 {r['t2m/R01']:.1f} %, R@5 {r['t2m/R05']:.1f} %, MedR {r['t2m/MedR']:g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

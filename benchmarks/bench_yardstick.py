"""Time the text-to-motion yardstick on 4,000 test pairs (issue #27, item 5: encoding, every
metric, 20 repeats in under 2 minutes on one core).

Usage:
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_yardstick.py [--n 4000] [--runs 3]
        [--evaluator RUN]   (default: a new evaluator of the default size; its weights do
                             not change the work done)

The 4,000 pairs are made here: motion rows of the ``kit`` body (251 values, 12.5 Hz) with
lengths drawn like the procedural corpus' (2-10 s) and captions of 6-14 words; real rows and
captions cost the same to encode. Timed as ``evaluate-t2m --protocol guo`` does it for one
row of the table: embed every caption and motion, the 20 shuffles of R-precision top-1/2/3,
FID (against another 4,000 motions, embedded too), MM-Dist and Diversity, then TMR's
retrieval among all pairs. Prints each part's median over ``--runs`` and the total against
the 120 s target; one thread (torch and BLAS), the baseline the project measures against.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))

TARGET_S = 120.0
WORDS = ("a person walks forward slowly then turns left and waves with the right hand "
         "runs jumps twice kicks squats raises both arms sits down on chair").split()


def make_pairs(n: int, seed: int = 0):
    """n motion rows (T-1, 251) float32 and n captions."""
    import numpy as np
    rng = np.random.default_rng(seed)
    rows = [rng.normal(size=(int(rng.integers(25, 126)), 251)).astype(np.float32)
            for _ in range(n)]
    caps = [" ".join(rng.choice(WORDS, size=int(rng.integers(6, 15)))) for _ in range(n)]
    return rows, caps


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=4000)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--evaluator", help="an evaluator file or run folder")
    args = ap.parse_args()

    import numpy as np
    import torch

    from motionlang.evaluation.t2m.yardstick import guo_metrics, retrieval_table
    from motionlang.models.evaluator.config import EvaluatorConfig
    from motionlang.models.evaluator.model import TextMotionEvaluator
    from motionlang.models.registry import load_model
    torch.set_num_threads(1)
    if args.evaluator:
        ev = load_model(args.evaluator, kind="evaluator")
    else:
        torch.manual_seed(0)
        ev = TextMotionEvaluator(EvaluatorConfig(), np.zeros(251), np.ones(251))
    rows, caps = make_pairs(args.n)
    real, _ = make_pairs(args.n, seed=1)
    parts: dict[str, list[float]] = {}
    for _ in range(args.runs):
        t = [time.perf_counter()]
        text = ev.embed_texts(caps)
        t.append(time.perf_counter())
        motion = ev.embed_motions(rows)
        real_emb = ev.embed_motions(real)
        t.append(time.perf_counter())
        guo_metrics(text, motion, real_emb, repeats=20)
        t.append(time.perf_counter())
        retrieval_table(text, motion)
        t.append(time.perf_counter())
        for name, a, b in zip(("captions", "motions (2 x n)", "20 repeats", "retrieval"),
                              t, t[1:]):
            parts.setdefault(name, []).append(b - a)
        parts.setdefault("total", []).append(t[-1] - t[0])
    print(f"{args.n} pairs, one thread, median of {args.runs} runs:")
    for name, times in parts.items():
        print(f"  {name:16s} {statistics.median(times):7.1f} s")
    total = statistics.median(parts["total"])
    print(f"total {total:.1f} s against the target {TARGET_S:.0f} s: "
          f"{'met' if total < TARGET_S else 'missed'} ({total / TARGET_S:.2f} of it)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

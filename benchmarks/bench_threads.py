"""How many torch threads ``--threads`` should default to: 1 vs 2 threads, idle vs busy CPU.

    .venv/bin/python benchmarks/bench_threads.py [--repeats 3] [--rounds 3]

Two representative workloads on the packaged M2L (real size, synthetic inputs):
  * ``train``: 4 optimiser steps (NAdam) on batches of 32 random motions of 30..80 frames;
  * ``describe``: beam search (width 5) over 12 random 10 s motions, as ``evaluate`` does.
Each runs in a fresh process per setting: ``OMP=1`` (the baseline: ``OMP_NUM_THREADS=1``,
nothing else set), ``threads 1`` / ``threads 2`` (``torch.set_num_threads`` and threadpoolctl,
what ``--threads N`` does) and ``torch default`` (no limit at all); once on the machine as it
is and once with an extra process spinning on one core. The settings take turns, round after
round, each in a fresh process timing ``--repeats`` runs; printed: the baseline's median
seconds and each setting's median as a ratio to it under the same load (> 1: slower).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "src" / "motionlang" / "data" / "models" / "m2l.pt"
SETTINGS = {"OMP=1": None, "threads 1": 1, "threads 2": 2, "torch default": 0}


def child(workload: str, threads: int | None, repeats: int) -> None:
    """Run in a fresh process: time ``workload`` and print {"median": seconds}."""
    import numpy as np
    import torch

    from motionlang.models.seq2seq.decode.search import describe_features
    from motionlang.models.seq2seq.m2l import MotionToLanguage
    from motionlang.training.collate import collate_pairs
    if threads:
        from threadpoolctl import threadpool_limits
        torch.set_num_threads(threads)
        threadpool_limits(threads)
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    model = MotionToLanguage.load(MODEL)
    F, V = model.config.n_features, model.config.vocab_size

    def batch():
        return collate_pairs([{"motion": rng.normal(size=(int(rng.integers(30, 80)), F))
                               .astype(np.float32),
                               "tokens": [1, *rng.integers(4, V, int(rng.integers(6, 16))), 2]}
                              for _ in range(32)])
    batches = [batch() for _ in range(4)]
    motions = [rng.normal(size=(100, F)).astype(np.float32) for _ in range(12)]
    opt = torch.optim.NAdam(model.parameters(), lr=1e-4)

    def train():
        model.train()
        for b in batches:
            opt.zero_grad()
            model.loss(b)["loss"].backward()
            opt.step()

    def describe():
        for m in motions:
            describe_features(model, m, width=5)
    fn = {"train": train, "describe": describe}[workload]
    fn()   # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    print(json.dumps({"median": statistics.median(times)}))


def measure(workload: str, setting: str, repeats: int) -> float:
    threads = SETTINGS[setting]
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    if setting == "OMP=1":
        env["OMP_NUM_THREADS"] = "1"
    out = subprocess.run([sys.executable, __file__, "--child", workload,
                          "--threads", str(threads or 0), "--repeats", str(repeats)],
                         env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])["median"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3,
                    help="timed runs per process, their median kept (default 3)")
    ap.add_argument("--rounds", type=int, default=3,
                    help="fresh processes per setting, interleaved; median of them (default 3)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--threads", type=int, default=0, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.child, a.threads or None, a.repeats)
        return
    print(f"{os.cpu_count()} CPUs; load average {os.getloadavg()[0]:.2f} at the start")
    for load in ("as is", "+1 busy core"):
        spinner = None
        if load != "as is":
            spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        try:
            for workload in ("train", "describe"):
                # settings interleaved, round after round, so that a change in the other
                # processes' load hits every setting alike; the median of the rounds
                times: dict[str, list[float]] = {k: [] for k in SETTINGS}
                for _ in range(a.rounds):
                    for setting in SETTINGS:
                        times[setting].append(measure(workload, setting, a.repeats))
                med = {k: statistics.median(v) for k, v in times.items()}
                base = med["OMP=1"]
                cells = [f"OMP=1 {base:.2f} s"] + [f"{k} {med[k] / base:.2f}x"
                                                   for k in SETTINGS if k != "OMP=1"]
                print(f"{load:13s} {workload:9s} " + " | ".join(cells), flush=True)
        finally:
            if spinner is not None:
                spinner.kill()
                spinner.wait()
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()

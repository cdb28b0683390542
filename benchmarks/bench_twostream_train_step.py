"""Time of one two-stream training step (loss, backward, the trainer's optimiser step) on a
batch of B motions of T frames, with the README recipe's decoder (embedding and progress
read at every step, energy weight 10) and every paper loss. Random weights and data: the
time does not depend on them. Token features are random too (the frozen text model is not
timed: training reads them from its per-sentence cache).

With ``--baseline REV`` the same step of the code at git revision REV (its ``src/`` taken
with ``git archive`` into a temporary folder) runs beside today's, each in its own worker
process, the two taking turns step by step, so that both see the same load on a shared
machine. Printed per code: the median (min, max) of the timed steps after one warm-up step,
in wall-clock and in CPU seconds of the worker (less sensitive to other processes), and the
loss after the last step (the same code gives the same loss: a check that a faster version
computes the same thing); and the load average before and after.

    .venv/bin/python benchmarks/bench_twostream_train_step.py [--steps 7] [--threads 1]
        [--h 128] [--batch 32] [--frames 125] [--baseline REV]
    # the paper's size: --h 512 --frames 32
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def worker(threads: int, h: int, B: int, T: int) -> None:
    """In a worker process: one line on stdin -> one training step -> one JSON line."""
    import torch

    import motionlang
    from motionlang.models.twostream.config import TwoStreamConfig
    from motionlang.models.twostream.model import TwoStreamModel
    from motionlang.training.trainer import OPTIMIZERS
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    cfg = TwoStreamConfig(h=h, z_every_step=True, progress_input=True, text_dim=1536,
                          lambdas={"energy": 10.0})
    model = TwoStreamModel(cfg, text_encoder=object()).train()   # token features given
    g = torch.Generator().manual_seed(0)
    lengths = torch.full((B,), T)
    lengths[B // 2:] = max(1, T - T // 5)             # a bucket: lengths close, not equal
    batch = {"motion": torch.randn(B, T, cfg.n_features, generator=g), "lengths": lengths,
             "text": torch.randn(B, 12, 1536, generator=g),
             "text_lengths": torch.full((B,), 12)}
    opt = OPTIMIZERS["nadam"](model.parameters(), lr=1e-4)
    print(json.dumps({"ready": str(Path(motionlang.__file__).parent)}), flush=True)
    for _ in sys.stdin:
        t0, c0 = time.perf_counter(), time.process_time()
        out = model.loss(batch)
        opt.zero_grad()
        out["loss"].backward()
        opt.step()
        print(json.dumps({"wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
                          "loss": float(out["loss"].detach())}), flush=True)


def baseline_tree(rev: str, into: Path) -> Path:
    """``src/`` of git revision ``rev`` (without the packaged data) under ``into``."""
    tar = into / "src.tar"
    with open(tar, "wb") as f:
        subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src/motionlang",
                        ":(exclude)src/motionlang/data"], stdout=f, check=True)
    with tarfile.open(tar) as t:
        t.extractall(into, filter="data")
    return into / "src"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=7)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--h", type=int, default=128)
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--frames", type=int, default=125)
    ap.add_argument("--baseline", metavar="REV", help="also time the code of this git revision")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        worker(a.threads, a.h, a.batch, a.frames)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        codes = {"today": ROOT / "src"}
        if a.baseline:
            codes = {a.baseline: baseline_tree(a.baseline, Path(tmp)), **codes}
        env = {**os.environ, "OMP_NUM_THREADS": str(a.threads), "MKL_NUM_THREADS": str(a.threads)}
        args = [sys.executable, __file__, "--worker", "--threads", str(a.threads), "--h",
                str(a.h), "--batch", str(a.batch), "--frames", str(a.frames)]
        procs = {name: subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        text=True, env={**env, "PYTHONPATH": str(src)})
                 for name, src in codes.items()}
        for name, p in procs.items():
            ready = json.loads(p.stdout.readline())["ready"]   # type: ignore[union-attr]
            print(f"{name}: {ready}")
        load = os.getloadavg()
        runs: dict[str, list[dict]] = {name: [] for name in procs}
        for _ in range(a.steps + 1):          # the first step warms up the allocator
            for name, p in procs.items():
                p.stdin.write("step\n")       # type: ignore[union-attr]
                p.stdin.flush()               # type: ignore[union-attr]
                runs[name].append(json.loads(p.stdout.readline()))   # type: ignore[union-attr]
        for p in procs.values():
            p.stdin.close()                   # type: ignore[union-attr]
            p.wait()
    print(f"two-stream training step, B={a.batch}, T={a.frames}, h={a.h}, {a.threads} "
          f"thread(s), {a.steps} steps each, taking turns; load average "
          f"{load[0]:.2f} before, {os.getloadavg()[0]:.2f} after")
    for name, rs in runs.items():
        timed = rs[1:]
        line = [f"{name:>12}:"]
        for key in ("wall", "cpu"):
            v = [1000 * r[key] for r in timed]
            line.append(f"{key} median {statistics.median(v):.0f} ms "
                        f"(min {min(v):.0f}, max {max(v):.0f});")
        print(" ".join(line), f"loss after the last step {rs[-1]['loss']:.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

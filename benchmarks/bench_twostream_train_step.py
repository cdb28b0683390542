"""Time of one two-stream training step (loss, backward, optimiser step) on a batch of
B motions of T frames, with the README recipe's decoder (embedding and progress read at
every step, energy weight 10) and every paper loss. Random weights and data: the time does
not depend on them. Token features are random too (the frozen text model is not timed:
training reads them from its per-sentence cache).

Prints the median (min, max) of the timed steps after one warm-up step, and the loss of
the last step (the same code gives the same loss: a check that a faster version computes
the same thing).

    .venv/bin/python benchmarks/bench_twostream_train_step.py [STEPS] [THREADS] [H] [B] [T]
"""
from __future__ import annotations

import statistics
import sys
import time

import torch

from motionlang.models.twostream import TwoStreamConfig, TwoStreamModel


def main() -> int:
    steps, threads, h, B, T = ([int(a) for a in sys.argv[1:6]]
                               + [7, 1, 128, 32, 125][len(sys.argv[1:6]):])
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
    opt = torch.optim.NAdam(model.parameters(), 1e-4)
    times, loss = [], float("nan")
    for i in range(steps + 1):
        t0 = time.perf_counter()
        out = model.loss(batch)
        opt.zero_grad()
        out["loss"].backward()
        opt.step()
        if i:   # the first step warms up the allocator
            times.append(time.perf_counter() - t0)
        loss = float(out["loss"].detach())
    print(f"two-stream training step, B={B}, T={T}, h={h}, {threads} thread(s), {steps} steps: "
          f"median {1000 * statistics.median(times):.0f} ms (min {1000 * min(times):.0f}, "
          f"max {1000 * max(times):.0f}); loss after the last step {loss:.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Latency of masked-token in-betweening against its number of drafts: a 10-second motion
(12.5 Hz -> 125 frames) with its middle 2 seconds regenerated from a sentence, feet held
(what ``generate --keep`` does), model loaded, for each number of drafts in the same run,
taking turns.

The motion filled in is one the model generates first (no data needed); the time does not
depend on which motion it is, only on its length and the drafts. Prints the median (min,
max) per number of drafts and its ratio to the first.

    .venv/bin/python benchmarks/bench_masked_inbetween.py [MODEL] [REPEAT] [THREADS] [DRAFTS ...]
    # defaults: masked 5 1 8 32
"""
from __future__ import annotations

import statistics
import sys
import time
from dataclasses import replace

import numpy as np
import torch


def main() -> int:
    import motionlang as ml
    from motionlang.errors import MotionlangError

    spec = sys.argv[1] if len(sys.argv) > 1 else "masked"
    repeat = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    threads = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    counts = [int(a) for a in sys.argv[4:]] or [8, 32]
    torch.set_num_threads(threads)
    try:
        model = ml.load_model(spec, kind="masked")
    except MotionlangError as exc:
        print(f"skipped: {exc}")
        return 0
    options = ml.text_to_motion(model).options
    sentence = "a person walks forward and then turns around"
    p21 = model.sample([sentence], [125], seed=0, options=options)[0]
    keep = np.ones(len(p21), dtype=bool)
    keep[50:75] = False                                   # 4-6 s regenerated

    def once(n: int, seed: int) -> float:
        t0 = time.perf_counter()
        model.inbetween(sentence, p21, keep, seed=seed, options=replace(options, drafts=n),
                        foot_lock=True)
        return 1000 * (time.perf_counter() - t0)

    for n in counts:
        once(n, 0)                                        # warm-up
    times: dict[int, list[float]] = {n: [] for n in counts}
    for i in range(repeat):
        for n in counts:                                  # taking turns: the same load
            times[n].append(once(n, i + 1))
    base = statistics.median(times[counts[0]])
    print(f"masked in-betweening, {len(p21)} frames, {int((~keep).sum())} regenerated, feet "
          f"held, {threads} thread(s), {repeat} runs each:")
    for n, t in times.items():
        m = statistics.median(t)
        print(f"  {n:3d} drafts: median {m:.0f} ms (min {min(t):.0f}, max {max(t):.0f}), "
              f"{m / base:.2f}x {counts[0]} drafts")
    return 0


if __name__ == "__main__":
    sys.exit(main())

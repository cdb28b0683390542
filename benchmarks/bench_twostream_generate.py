"""Latency of two-stream text-to-motion generation: a 10-second motion (12.5 Hz -> 125
frames) from a sentence, sentence encoding by the frozen MiniLM included (its per-sentence
cache is cleared before every run, so each run pays the language model).

The model has the paper's sizes (h1 32, h2 128, h 512; h can be changed) and random weights: latency does not
depend on the weights. Prints the median (and min/max) of repeated runs; target < 200 ms.
``fed`` as a 4th argument times the decoder that reads its embedding and the clock at every
step (``--z-every-step --time-input``); ``progress`` the one that reads its embedding and the
fraction done (``--z-every-step --progress-input``, the README's recommended options).

    .venv/bin/python benchmarks/bench_twostream_generate.py [REPEAT] [THREADS] [H] [fed|progress]
"""
from __future__ import annotations

import statistics
import sys
import time

import torch

from motionlang.errors import MotionlangError
from motionlang.models.twostream.config import TwoStreamConfig
from motionlang.models.twostream.model import TwoStreamModel

SENTENCES = [
    "a person walks forward four steps, turns around and waves with the right hand",
    "someone jogs in a circle and then jumps twice",
    "a human raises both arms while walking slowly backwards",
]


def main() -> int:
    repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 15
    threads = int(sys.argv[2]) if len(sys.argv) > 2 else 1
    h = int(sys.argv[3]) if len(sys.argv) > 3 else 512
    variant = sys.argv[4] if len(sys.argv) > 4 else ""
    if variant not in ("", "fed", "progress"):
        sys.exit(f"unknown 4th argument {variant!r}: 'fed' or 'progress'")
    torch.set_num_threads(threads)
    try:
        model = TwoStreamModel(TwoStreamConfig(
            h=h, z_every_step=bool(variant), time_input=variant == "fed",
            progress_input=variant == "progress")).eval()
    except MotionlangError as exc:
        print(f"skipped: {exc}")
        return 0
    n_frames = int(10 * 12.5)
    model.generate(SENTENCES[0], n_frames)  # warm-up (lazy init, allocator)
    times, text_times = [], []
    for i in range(repeat):
        model.text_encoder.clear_cache()
        s = SENTENCES[i % len(SENTENCES)]
        t0 = time.perf_counter()
        out = model.generate(s, n_frames)
        times.append(time.perf_counter() - t0)
        model.text_encoder.clear_cache()
        t0 = time.perf_counter()
        model.text_encoder.features(s)
        text_times.append(time.perf_counter() - t0)
    assert out.shape == (n_frames, model.config.n_features)
    ms = [1000 * t for t in times]
    print(f"two-stream generate, {n_frames} frames, h={model.config.h}"
          f"{', z + ' + ('clock' if variant == 'fed' else 'progress') + ' every step' if variant else ''}"
          f", {threads} thread(s), "
          f"{repeat} runs: median {statistics.median(ms):.1f} ms "
          f"(min {min(ms):.1f}, max {max(ms):.1f}); of which sentence encoding median "
          f"{1000 * statistics.median(text_times):.1f} ms; target < 200 ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Latency of masked-token text-to-motion generation: a 10-second motion (12.5 Hz -> 125
frames) from a sentence, model loaded, with its default sampling options (masked decoding,
classifier-free guidance on both transformers), global positions out.

Two figures: with the sentence's vector cached (the model asked again for a sentence it has
seen: ``generate`` of several motions, the evaluators) and with a new sentence each run
(MiniLM's per-sentence cache cleared, so each run pays the language model). Prints medians
(and min/max) of repeated runs; the issue's target is 50 ms.

    .venv/bin/python benchmarks/bench_masked_generate.py [MODEL] [REPEAT] [THREADS] [STEPS]

MODEL: a run folder or model file (default: a model of the default sizes with random
weights: latency does not depend on the weights, but a trained model's length estimator is
not used here: the length is given).
"""
from __future__ import annotations

import statistics
import sys
import time

import torch

SENTENCES = [
    "a person walks forward four steps, turns around and waves with the right hand",
    "someone jogs in a circle and then jumps twice",
    "a human raises both arms while walking slowly backwards",
]


def main() -> int:
    from motionlang.errors import MotionlangError
    from motionlang.models.masked.config import MaskedConfig, MaskedOptions
    from motionlang.models.masked.model import MaskedModel

    spec = sys.argv[1] if len(sys.argv) > 1 else ""
    repeat = int(sys.argv[2]) if len(sys.argv) > 2 else 15
    threads = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    options = MaskedOptions(**({"steps": int(sys.argv[4])} if len(sys.argv) > 4 else {}))
    torch.set_num_threads(threads)
    try:
        if spec:
            import motionlang as ml
            model = ml.load_model(spec)
        else:
            model = MaskedModel(MaskedConfig(), None).eval()
    except MotionlangError as exc:
        print(f"skipped: {exc}")
        return 0
    n_frames = 125
    n_tok = n_frames // 4 + 1

    def once(sentence: str, seed: int) -> None:
        if model.features is not None and model.features.fitted:
            model.sample([sentence], [n_frames], seed=seed, options=options)
        else:   # random weights: tokens and rows, no positions to decode
            tokens = model.sample_tokens([sentence], [n_tok], seed=seed, options=options)
            model.tokenizer.decode(tokens)

    once(SENTENCES[0], 0)   # warm-up: lazy init, allocator, the text encoder
    cached, fresh = [], []
    for i in range(repeat):
        s = SENTENCES[i % len(SENTENCES)]
        model.text.clear_cache()
        t0 = time.perf_counter()
        once(s, i)              # the sentence is new to the model: the language model runs
        fresh.append(1000 * (time.perf_counter() - t0))
        t0 = time.perf_counter()
        once(s, i)              # the same sentence again: its vector is cached
        cached.append(1000 * (time.perf_counter() - t0))
    sizes = (f"hidden {model.config.hidden}, {model.config.layers}+{model.config.res_layers} "
             f"layers, {model.config.quantizers} codebooks")
    print(f"masked generate, {n_frames} frames, {sizes}, {options.steps} steps, guidance "
          f"{options.guidance}/{options.res_guidance}, {threads} thread(s), {repeat} runs: "
          f"sentence cached: median {statistics.median(cached):.1f} ms (min {min(cached):.1f}, "
          f"max {max(cached):.1f}); new sentence: median {statistics.median(fresh):.1f} ms "
          f"(min {min(fresh):.1f}, max {max(fresh):.1f}); target <= 50 ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())

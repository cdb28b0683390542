"""Speed of the Plappert et al. (2018) seq2seq models at paper size on this CPU.

    .venv/bin/python benchmarks/bench_seq2seq.py [--features 50] [--vocab 1000] [--repeats 7]
        [--packaged] [--l2m MODEL]

Prints medians of repeated runs: training throughput (sequences/s, batch 128) of M2L and L2M,
``describe`` latency (beam width 5, batch 1, a 10 s motion at 10 Hz) and ``generate``
latency of a 10-second motion (100 frames at 10 Hz: sampled beam, width 5, 5 samples; W = 5
ancestral samples, the CLI's default; mean decoding).
Weights are random (speed does not depend on training); the L2M "active" bias is set high so
every hypothesis runs the full 100 frames. Uses 1 thread unless --threads says otherwise.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import torch

from motionlang.models.seq2seq.decode.search import describe_features, generate_features
from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
from motionlang.models.seq2seq.m2l import M2LConfig, MotionToLanguage
from motionlang.training.collate import collate_pairs


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def fake_batch(rng, B, F, V, T=(30, 80), L=(6, 16)):
    items = [{"motion": rng.normal(size=(int(rng.integers(*T)), F)).astype(np.float32),
              "tokens": [1, *rng.integers(4, V, int(rng.integers(*L))).tolist(), 2]}
             for _ in range(B)]
    return collate_pairs(items)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--features", type=int, default=50)
    ap.add_argument("--vocab", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--packaged", action="store_true",
                    help="time the packaged (shipped) models instead of paper-size ones")
    ap.add_argument("--l2m", metavar="MODEL", help="with --packaged: time this L2M file "
                    "(e.g. one trained with --plan-parts) instead of the packaged one")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    F, V = args.features, args.vocab
    if args.packaged:
        from motionlang.models.registry import load_model
        m2l = load_model("m2l", kind="m2l")
        l2m = load_model(args.l2m or "l2m", kind="l2m")
        F, V = m2l.config.n_features, m2l.config.vocab_size
        print(f"packaged models: M2L {m2l.config}\nL2M {l2m.config}")
    elif args.l2m:
        raise SystemExit("--l2m needs --packaged (its M2L ranks and describes)")
    else:
        m2l = MotionToLanguage(M2LConfig(n_features=F, vocab_size=V))
        l2m = LanguageToMotion(L2MConfig(vocab_size=V, n_features=F))
    batch = fake_batch(rng, 128, F, V)
    for name, model in (("m2l", m2l), ("l2m", l2m)):
        opt = torch.optim.NAdam(model.parameters(), lr=1e-3)
        model.train()

        def train_step(opt=opt, model=model):
            opt.zero_grad()
            model.loss(batch)["loss"].backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 25.0)
            opt.step()
        t = median_time(train_step, max(3, args.repeats // 2))
        print(f"{name} train: {128 / t:8.1f} sequences/s  "
              f"(batch 128, median {t * 1e3:.0f} ms/step)")
    m2l.eval()
    motion = rng.normal(size=(100, F)).astype(np.float32)
    t = median_time(lambda: describe_features(m2l, motion, width=5, max_len=20), args.repeats)
    print(f"describe (W=5, 100 frames, <=20 words): median {t * 1e3:.1f} ms")
    l2m.eval()
    with torch.no_grad():
        l2m.head.proj.bias[-1] = 30.0     # always active -> full 100 frames
    t = median_time(lambda: generate_features(l2m, [1, 5, 6, 7, 2], width=5, max_frames=100),
                    args.repeats)
    print(f"generate (W=5, 5 samples, 100 frames = 10 s at 10 Hz): median {t * 1e3:.1f} ms")
    t = median_time(lambda: generate_features(l2m, [1, 5, 6, 7, 2], method="mean",
                                              max_frames=100), args.repeats)
    print(f"generate (mean decoding, 100 frames): median {t * 1e3:.1f} ms")
    t = median_time(lambda: generate_features(l2m, [1, 5, 6, 7, 2], width=5, method="sample",
                                              max_frames=100), args.repeats)
    print(f"generate (W=5 ancestral samples, 100 frames): median {t * 1e3:.1f} ms")
    from motionlang.models.seq2seq.decode.rerank import rerank
    for w in (5, 10, 30, 60):
        t = median_time(lambda w=w: rerank(generate_features(
            l2m, [1, 5, 6, 7, 2], width=w, method="sample", max_frames=100), m2l,
            [1, 5, 6, 7, 2]), args.repeats)
        print(f"generate (W={w} ancestral samples ranked by the M2L, 100 frames): "
              f"median {t * 1e3:.1f} ms")


if __name__ == "__main__":
    main()

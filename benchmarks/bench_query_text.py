"""How long a query's text takes, with the model loaded: the sentence through the frozen
encoder and the text projection (``embed_texts``), for each retrieval model given (the
packaged one reads MiniLM; a model trained with ``--text-model mpnet`` reads mpnet).

Every query is a sentence not seen before (the encoder caches sentences it has read): the
median over ``--queries`` of them, after one warm-up query. Threads: ``--threads``.

    .venv/bin/python benchmarks/bench_query_text.py retrieval [RUN/model.pt ...] [--threads 2]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time

VERBS = ("walks", "runs", "jumps", "waves", "kicks", "sits down", "turns left", "bows",
         "crawls", "claps")
HOW = ("slowly", "quickly", "forward", "in a circle", "twice", "with the left hand",
       "backwards", "to the right", "happily", "three times")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="+")
    ap.add_argument("--queries", type=int, default=40)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    import torch
    torch.set_num_threads(args.threads)
    import motionlang as ml
    sentences = [f"someone {v} {h}" for v in VERBS for h in HOW]
    for name in args.models:
        model = ml.load_model(name, kind="retrieval")
        model.embed_texts(["a person stands still"])   # loads the encoder
        times = []
        for i in range(args.queries):
            s = f"{sentences[i % len(sentences)]} ({name}, {i})"   # never cached
            t0 = time.perf_counter()
            model.embed_texts([s])
            times.append(time.perf_counter() - t0)
        print(f"{name}: text model {model.config.text_model}, a query's text "
              f"{1e3 * statistics.median(times):.1f} ms median "
              f"({args.queries} new sentences, {args.threads} threads)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A small text head over MiniLM trained to reproduce all-mpnet-base-v2's sentence vectors on
motion sentences: the best of both, at MiniLM's speed and without the 405 MB download.

    OMP_NUM_THREADS=2 .venv/bin/python experiments/distil_text_head.py \\
        --corpus /tmp/corpus --bandai ../shared/data/bandai \\
        --kitml ../shared/data/kitml/annotations_tmr.json \\
        --out src/motionlang/data/text_heads/minilm_mpnet.npz

Sentences: every caption of the procedural corpus, of the Bandai takes (their grammar) and
KIT-ML's real annotations, and two rewrites of each (its canonical form,
``datasets.canonical``, and the sentence without its style words), each once. Both encoders
read them all (mean-pooled last layer: the sentence vectors the retrieval family reads);
the head, ``mpnet ~ W2 gelu(W1 minilm + b1) + b2 + P minilm`` (a linear part and a one-layer
residual), is fitted on 90 % of the sentences (chosen by hash) by the cosine to mpnet's
vector plus the match of the two within-batch cosine matrices, and judged on the other 10 %
and on the queries of ``experiments/retrieval_bandai.py`` (which no caption uses): cosine
to mpnet, and how often the 10 nearest training sentences of mpnet are the head's too.
Writes the head (float16, with its provenance) for ``--text-model minilm-mpnet``.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch

from motionlang.datasets.canonical import canonical_text, without_style
from motionlang.models.retrieval.text import SentenceVectors, cache_file
from motionlang.models.text_tokens import TransformerTokens


def sentences(corpus: str | None, bandai: str | None, kitml: str | None) -> list[str]:
    from motionlang.datasets.seq2seq_pairs import load_records
    found: list[str] = []
    for src in [s for s in (corpus, f"bandai:{bandai}" if bandai else None) if s]:
        found += [a for r in load_records(src, None) for a in r.annotations]
    if kitml:
        data = json.loads(Path(kitml).read_text())
        found += [a["text"] for v in data.values() for a in v["annotations"]]
    out = []
    for s in found:
        out += [s.strip(), canonical_text(s), without_style(s)]
    return sorted({s for s in out if s})


def vectors(name: str, texts: list[str]) -> np.ndarray:
    sv = SentenceVectors(TransformerTokens(name, (-1,), cache_size=1024))
    kept = cache_file(name, 0)
    sv.load(kept)
    t0 = time.perf_counter()
    out = np.concatenate([sv.vectors(texts[i:i + 256]).numpy()
                          for i in range(0, len(texts), 256)])
    sv.save(kept)
    print(f"{name}: {len(texts)} sentences in {time.perf_counter() - t0:.0f} s", flush=True)
    return out


class Head(torch.nn.Module):
    def __init__(self, d_in: int, d_out: int, hidden: int):
        super().__init__()
        self.linear = torch.nn.Linear(d_in, d_out, bias=False)
        self.w1 = torch.nn.Linear(d_in, hidden)
        self.w2 = torch.nn.Linear(hidden, d_out)

    def forward(self, x):
        return self.linear(x) + self.w2(torch.nn.functional.gelu(self.w1(x)))


def unit(x):
    return x / x.norm(dim=-1, keepdim=True).clamp_min(1e-8)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--corpus")
    ap.add_argument("--bandai")
    ap.add_argument("--kitml")
    ap.add_argument("--out", required=True)
    ap.add_argument("--hidden", type=int, default=768)
    ap.add_argument("--epochs", type=int, default=60)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    torch.manual_seed(args.seed)
    texts = sentences(args.corpus, args.bandai, args.kitml)
    from retrieval_bandai import QUERIES  # experiments/: the probe, never trained on
    probe = sorted(set(QUERIES.values()))
    x, y = vectors("minilm", texts + probe), vectors("mpnet", texts + probe)
    n = len(texts)
    held = np.array([int(hashlib.sha256(t.encode()).hexdigest()[:4], 16) % 10 == 0
                     for t in texts])
    xt, yt = torch.from_numpy(x), torch.from_numpy(y)
    mu_x, sd_x = xt[:n][~held].mean(0), xt[:n][~held].std(0) + 1e-6
    head = Head(x.shape[1], y.shape[1], args.hidden)
    opt = torch.optim.AdamW(head.parameters(), lr=1e-3, weight_decay=1e-4)
    train = np.flatnonzero(~held)
    for epoch in range(args.epochs):
        perm = np.random.default_rng(epoch).permutation(train)
        for b in range(0, len(perm), 256):
            idx = torch.from_numpy(perm[b:b + 256])
            got, want = unit(head((xt[idx] - mu_x) / sd_x)), unit(yt[idx])
            loss = (1 - (got * want).sum(-1)).mean() + \
                ((got @ got.T - want @ want.T) ** 2).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
    with torch.no_grad():
        pred = unit(head((xt - mu_x) / sd_x)).numpy()
    want = (yt / yt.norm(dim=-1, keepdim=True)).numpy()
    base = x / np.linalg.norm(x, axis=1, keepdims=True)

    def neighbours(a: np.ndarray, rows: np.ndarray, k: int = 10) -> np.ndarray:
        s = a[rows] @ a[train].T
        return np.argsort(-s, axis=1)[:, :k]

    for name, rows in (("held-out sentences", np.flatnonzero(held)),
                       ("probe queries", np.arange(n, len(texts) + len(probe)))):
        cos = (pred[rows] * want[rows]).sum(1).mean()
        nn_want = neighbours(want, rows)
        agree = {k: np.mean([len(set(a) & set(b)) / 10 for a, b in zip(
            neighbours(v, rows), nn_want)]) for k, v in (("head", pred), ("minilm", base))}
        print(f"{name} ({len(rows)}): cosine to mpnet {cos:.3f}; mpnet's 10 nearest training "
              f"sentences shared: head {agree['head']:.2f}, MiniLM alone {agree['minilm']:.2f}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    state = {k: v.detach().numpy().astype(np.float16) for k, v in head.state_dict().items()}
    np.savez(out, mu=mu_x.numpy(), sd=sd_x.numpy(), **state,
             meta=np.array(json.dumps({"from": "minilm", "to": "mpnet", "hidden": args.hidden,
                                       "sentences": n, "epochs": args.epochs,
                                       "seed": args.seed})))
    print(f"{out}: {out.stat().st_size / 2**20:.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    sys.exit(main())

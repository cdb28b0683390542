"""Does an L2M model's sentence context hold what its motions should do? Linear probes on the
context vectors (the encoder's output that every decoder step reads) of the validation and
test pairs of a procedural corpus:

* cross-validated R^2 of a ridge regression from the context to each root feature's mean over
  the motion (``root_vz`` forward speed, ``root_vx`` sideways, ``root_dyaw`` turning);
* cross-validated accuracy of a logistic regression telling apart motions with one
  ground-truth primitive but not the other (walking left vs right, backward vs forward),
  beside the same probe on the context of an untrained model of the same configuration.

A context that separates "backwards" from "forward" while the generated motions do not shows
that the decoder, not the encoder, drops the word.

    .venv/bin/python experiments/probes/l2m_context_probe.py --data corpus [--model M]
"""
from __future__ import annotations

import argparse

import numpy as np
import torch

PAIRS = (("walk/left", "walk/right"), ("walk/backward", "walk/forward"))
ROOT = ("root_vz", "root_vx", "root_dyaw")


def contexts(model, items: list[dict], batch: int = 256) -> np.ndarray:
    """(N, C) context vectors of the items' sentences."""
    from motionlang.training.collate import collate_pairs
    out = []
    with torch.no_grad():
        for i in range(0, len(items), batch):
            b = collate_pairs(items[i:i + batch])
            out.append(model.encode(b["tokens"], b["token_lengths"])["context"].numpy())
    return np.concatenate(out)


def ridge_r2(x: np.ndarray, y: np.ndarray, folds: int = 5) -> float:
    """Cross-validated R^2 of a ridge regression x -> y (penalty chosen inside each fold)."""
    from sklearn.linear_model import RidgeCV
    from sklearn.model_selection import cross_val_predict
    pred = cross_val_predict(RidgeCV(alphas=np.logspace(-3, 3, 13)), x, y, cv=folds)
    return float(1.0 - ((pred - y) ** 2).sum() / ((y - y.mean()) ** 2).sum())


def probe_accuracy(x: np.ndarray, y: np.ndarray, folds: int = 5) -> float:
    """Cross-validated accuracy of a logistic regression x -> y (bool)."""
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import cross_val_predict
    pred = cross_val_predict(LogisticRegression(C=1.0, max_iter=5000), x, y, cv=folds)
    return float((pred == y).mean())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="the procedural corpus the model was trained on")
    ap.add_argument("--model", default=None, help="L2M model file (default: packaged)")
    ap.add_argument("--folds", type=int, default=5)
    args = ap.parse_args(argv)
    torch.set_num_threads(1)

    import motionlang as ml
    from motionlang.datasets.seq2seq_pairs import build_pairs
    from motionlang.models.registry import resolve
    from motionlang.models.seq2seq.l2m import LanguageToMotion
    path = resolve(args.model or "l2m")
    model = ml.load_model(path, kind="l2m")
    fs = model.features
    missing = [n for n in ROOT if n not in fs.names]
    if missing:
        raise SystemExit(f"{path}: the model's features have no {', '.join(missing)}")
    from motionlang.models.seq2seq.decode.search import encode_sentence
    # the split of the shipped runs (seed 0); sentences re-encoded in the model's vocabulary
    data = build_pairs(args.data, features=fs.kind, offsets=1, seed=0)
    items = [{**it, "tokens": encode_sentence(model.vocab, data.vocab.decode(it["tokens"]))}
             for split in ("val", "test") for it in data.items.get(split, [])]
    if len(items) < 2 * args.folds:
        raise SystemExit(f"{args.data}: {len(items)} held-out pairs, too few for "
                         f"{args.folds} folds")
    x = contexts(model, items)
    torch.manual_seed(0)
    fresh = contexts(LanguageToMotion(model.config, model.vocab).eval(), items)
    print(f"{len(items)} validation/test pairs; context {x.shape[1]}-d, mean |value| "
          f"{np.abs(x).mean():.3f}")
    cols = [fs.names.index(n) for n in ROOT]
    y = np.array([it["motion"][:, cols].mean(axis=0) for it in items])
    for j, name in enumerate(ROOT):
        print(f"  {name}: R^2 of the motion's mean from the context "
              f"{ridge_r2(x, y[:, j], args.folds):.3f}")
    labels = [data.labels.get(it["id"], []) for it in items]
    for a, b in PAIRS:
        idx = [k for k, lab in enumerate(labels) if (a in lab) != (b in lab)]
        target = np.array([a in labels[k] for k in idx])
        if len(idx) < 2 * args.folds or target.all() or not target.any():
            print(f"  {a} vs {b}: too few pairs ({len(idx)})")
            continue
        print(f"  {a} vs {b}: {len(idx)} pairs ({int(target.sum())} {a}); probe accuracy "
              f"{probe_accuracy(x[idx], target, args.folds):.3f} (untrained model "
              f"{probe_accuracy(fresh[idx], target, args.folds):.3f}; majority "
              f"{max(target.mean(), 1 - target.mean()):.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

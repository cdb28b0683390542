"""How well does an L2M model predict each feature of the next frame, fed the true previous
frames (teacher forcing, eval mode)? On held-out pairs, per feature (default: the root's
motion), in normalised units:

* ``lag-1``: the data's own correlation between consecutive frames (what copying the
  previous frame would reach);
* ``corr``: the correlation between the model's expected frame sum_k pi_k mu_k and the
  true frame;
* ``sigma``: the mixture's mean standard deviation (weighted by pi), beside the data's.

A model whose ``corr`` is far below ``lag-1``, or negative, does not take that feature from
the frames it is shown: fed its own frames, it will not keep a turn or a sideways walk going.

    .venv/bin/python experiments/probes/l2m_feature_fit.py --data corpus [--model M] [--split val]
"""
from __future__ import annotations

import argparse

import numpy as np
import torch

ROOT = ("root_vx", "root_vz", "root_dyaw", "root_height")


def feature_fit(model, items: list[dict], columns: list[int]) -> dict[int, dict]:
    """Per column: ``lag1``, ``corr``, ``sigma`` (mixture), ``std`` (data) over valid frames
    1..T-1 of each item (frame 0 has no true previous frame)."""
    from motionlang.models.seq2seq import mdn
    from motionlang.training.collate import collate_pairs
    b = collate_pairs(items)
    B, T, F = b["motion"].shape
    with torch.no_grad():
        p = model(b["tokens"], b["token_lengths"], b["motion"], b["motion_lengths"]).flatten()
    expected = mdn.mixture_mean(p).reshape(B, T, F)
    pi = torch.softmax(p.logit_pi, -1).unsqueeze(-1)
    sigma = (pi * p.log_sigma.exp()).sum(1).reshape(B, T, F)
    keep = torch.arange(T)[None] < b["motion_lengths"][:, None]
    keep[:, 0] = False
    prev_keep = torch.roll(keep, -1, dims=1)              # frames t-1 of the kept frames t
    x = b["motion"]
    out = {}
    for c in columns:
        now, before = x[..., c][keep].numpy(), x[..., c][prev_keep].numpy()
        out[c] = {"lag1": float(np.corrcoef(now, before)[0, 1]),
                  "corr": float(np.corrcoef(now, expected[..., c][keep].numpy())[0, 1]),
                  "sigma": float(sigma[..., c][keep].mean()), "std": float(now.std())}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="the corpus the model was trained on")
    ap.add_argument("--model", default=None, help="L2M model file (default: packaged)")
    ap.add_argument("--split", default="val", choices=("train", "val", "test"))
    ap.add_argument("--features", default=",".join(ROOT), help="comma-separated names")
    ap.add_argument("--limit", type=int, default=128, help="at most N pairs")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)

    import motionlang as ml
    from motionlang.datasets.seq2seq_pairs import build_pairs
    from motionlang.features.frames import model_dim
    from motionlang.models.registry import resolve
    path = resolve(args.model or "l2m")
    model = ml.load_model(path, kind="l2m")
    names = list(model.features.names[:model_dim(model.features)])
    wanted = args.features.split(",")
    missing = [n for n in wanted if n not in names]
    if missing:
        raise SystemExit(f"{path}: no feature {', '.join(missing)} among the model's features")
    data = build_pairs(args.data, features=model.features.kind, offsets=1, seed=0)
    items = data.items.get(args.split, [])[:args.limit]
    if not items:
        raise SystemExit(f"{args.data}: the {args.split} split has no pairs")
    fit = feature_fit(model, items, [names.index(n) for n in wanted])
    print(f"{len(items)} {args.split} pairs, teacher-forced (normalised units):")
    for n in wanted:
        r = fit[names.index(n)]
        print(f"  {n:14s} lag-1 {r['lag1']:+.3f}  corr {r['corr']:+.3f}  "
              f"sigma {r['sigma']:.3f} (data std {r['std']:.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

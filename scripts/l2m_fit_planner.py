"""Fit the planner of an L2M trained with ``--plan-parts`` on its own, and save the model
with it: the decoder, its encoder and the rest are kept as they are.

    .venv/bin/python scripts/l2m_fit_planner.py MODEL --data corpus --out NEW.pt \
        [--epochs 30] [--fresh]

The planner maps a sentence to the coarse plan the decoder follows (``models.seq2seq.plan``); it
needs no decoder to be fitted, so many epochs take minutes. ``--fresh`` starts it from new
weights (and replaces whatever planner the file held). The training and validation pairs
are the ones ``train l2m`` made from the same corpus (split seed ``--seed``); the model's
features must be the corpus's.
"""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))   # experiments.lab


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", help="L2M model file trained with --plan-parts")
    ap.add_argument("--data", required=True, action="append",
                    help="the dataset(s) the model was trained on, as its --data (repeat it "
                         "for a mixed run, in the same order)")
    ap.add_argument("--mirror", action="store_true",
                    help="also fit on mirrored training motions (as a run with --mirror)")
    ap.add_argument("--out", required=True, help="where to write the model with its planner")
    ap.add_argument("--epochs", type=int, default=30)
    ap.add_argument("--batch-size", type=int, default=128)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--seed", type=int, default=0, help="split seed of the training run")
    ap.add_argument("--fresh", action="store_true", help="new planner weights")
    args = ap.parse_args(argv)
    import torch
    from experiments.lab.plan_fit import fit_planner

    from motionlang.datasets.seq2seq_pairs import build_pairs
    from motionlang.errors import MotionlangError
    from motionlang.models.checkpoint import read_model_dict
    from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
    from motionlang.models.seq2seq.plan import Planner

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        if args.epochs < 1:
            raise MotionlangError(f"--epochs must be >= 1, got {args.epochs}")
        d = read_model_dict(args.model, "l2m")
        c = L2MConfig(**d["config"])
        if not c.plan_parts:
            raise MotionlangError(f"{args.model}: this L2M has no plan (train it with "
                                  "--plan-parts)")
        if args.fresh:
            torch.manual_seed(args.seed)
            new = Planner.for_config(c).state_dict()
            # "plan_head.": the planner's first form, a head on the decoder's own sentence
            # context, which learnt too slowly (the runs of 2026-11-23 hold it)
            kept = {k: v for k, v in d["state_dict"].items()
                    if not k.startswith(("planner.", "plan_head."))}
            d = {**d, "state_dict": {**kept, **{f"planner.{k}": v for k, v in new.items()}}}
        model = LanguageToMotion.from_checkpoint(d)
        from motionlang.datasets.mixing import parse_source
        paths = [parse_source(d).path for d in args.data]   # DIR@W: the weights do not matter
        data = build_pairs(paths if len(paths) > 1 else paths[0],
                           features=model.features.kind, offsets=1, seed=args.seed,
                           mirror=args.mirror)
        if model.features.to_dict() != data.features.to_dict():
            raise MotionlangError(f"--data {args.data}: its features (fitted on its training "
                                  f"split, seed {args.seed}) differ from {args.model}'s")
        history = fit_planner(model, data.items["train"], data.items.get("val"),
                              epochs=args.epochs, batch_size=args.batch_size, lr=args.lr,
                              seed=args.seed)
    except MotionlangError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    best = min(history, key=lambda r: r.get("val", r["train"]))
    model.save(args.out)
    print(f"planner: epoch {best['epoch']} kept (train MSE {best['train']:.4f}"
          + (f", val MSE {best['val']:.4f}" if "val" in best else "") + f"); wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

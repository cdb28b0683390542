"""Train the sentence encoder of a trained two-stream model on its own, and save the model
with it: the pose encoder, the decoder and the discriminator are kept as they are.

    .venv/bin/python experiments/probes/twostream_fit_sentence.py MODEL --data corpus --out NEW.pt \
        [--epochs 2] [--lr 1e-3] [--weight pose=0 --weight energy=0]

Why: decoded from the motions' *own* pose embeddings, our models get the order of actions
right more often than from the sentence (README), so the sentence embedding, not the
decoder, is where orders are lost. The loss is the "text" stage of the no-joint-training
ablation (``recipes.twostream_train.refit_sentence_encoder``): the motion decoded from the
sentence embedding against the true one (pose, and energy with the model's weight) plus
the embedding term. ``--weight pose=0 --weight energy=0`` fits the embedding term alone
(nothing is decoded: a few minutes per epoch on the 6,000-motion corpus, the pose encoder
reading every motion). The training and validation pairs are those
``train twostream`` made from the same corpus (split seed ``--seed``, ``--max-seconds``,
``--max-frames``, ``--mirror``); the model's normaliser must be the corpus's. OUT keeps the
model's own loss weights and stage; the checkpoints in the run folder (``OUT_run``) are the
trainer's, in the "text" stage with this fit's weights.
"""
from __future__ import annotations

import argparse
import logging
import sys


def parse_weights(specs: list[str] | None) -> dict[str, float]:
    """``["pose=0", ...]`` -> {term: weight}; the terms and values are checked by the
    model's config when they are applied."""
    from motionlang.errors import MotionlangError
    out: dict[str, float] = {}
    for spec in specs or []:
        name, sep, value = spec.partition("=")
        try:
            if not sep or name in out:
                raise ValueError
            out[name] = float(value)
        except ValueError:
            raise MotionlangError(f"--weight {spec!r}: expected TERM=W, each term once") from None
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", help="a trained two-stream model file")
    ap.add_argument("--data", required=True, help="the corpus the model was trained on")
    ap.add_argument("--out", required=True, help="where to write the model")
    ap.add_argument("--run-dir", help="checkpoints and history (default: OUT_run)")
    ap.add_argument("--epochs", type=int, default=2)
    ap.add_argument("--batch-size", type=int, default=32)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--decay-epochs", type=float, default=0.0,
                    help="lower the rate along a half cosine over the last N epochs")
    ap.add_argument("--weight", action="append", metavar="TERM=W",
                    help="loss weights for this fit (default: the model's own)")
    ap.add_argument("--seed", type=int, default=0, help="split seed of the training run")
    ap.add_argument("--max-seconds", type=float, default=30.0)
    ap.add_argument("--max-frames", type=int, default=None)
    ap.add_argument("--length-buckets", type=int, default=20)
    ap.add_argument("--mirror", action="store_true",
                    help="also the mirrored training motions (as the model's run, if it had them)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--resume", action="store_true",
                    help="continue this fit from its run's last.pt (which holds the whole "
                         "model: MODEL is then only read for its settings)")
    args = ap.parse_args(argv)
    import dataclasses
    from pathlib import Path

    import numpy as np
    import torch

    import motionlang as ml
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.errors import MotionlangError
    from motionlang.recipes.twostream_train import refit_sentence_encoder
    from motionlang.training.config import TrainConfig
    from motionlang.training.schedule import check_schedule

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    torch.set_num_threads(max(1, args.threads))
    try:
        if args.epochs < 1:
            raise MotionlangError(f"--epochs must be >= 1, got {args.epochs}")
        check_schedule(args.decay_epochs, 0.01, args.epochs)
        out = Path(args.out)
        if out.suffix != ".pt":
            raise MotionlangError(f"{out}: the model file must end in .pt")
        lambdas = parse_weights(args.weight)
        model = ml.load_model(args.model, kind="twostream")
        own = dict(model.config.lambdas)
        # for this fit only, not saved; the config checks the terms and weights
        model.config.lambdas = dataclasses.replace(model.config,
                                                   lambdas={**own, **lambdas}).lambdas
        data = build_twostream_data(args.data, seed=args.seed, max_seconds=args.max_seconds,
                                    max_frames=args.max_frames, mirror=args.mirror)
        mine, theirs = model.normalizer, data.features.normalizer
        if mine is None or not (np.allclose(mine.mean, theirs.mean)
                                and np.allclose(mine.std, theirs.std)):
            raise MotionlangError(f"--data {args.data}: its features are not the ones "
                                  f"{args.model} was trained on (another corpus or split "
                                  "seed?)")
        run = Path(args.run_dir) if args.run_dir else out.parent / f"{out.stem}_run"
        cfg = TrainConfig(epochs=args.epochs, batch_size=args.batch_size, lr=args.lr,
                          grad_clip=5.0, seed=args.seed, out_dir=str(run),
                          length_buckets=args.length_buckets,
                          decay_epochs=args.decay_epochs)
        model, history = refit_sentence_encoder(model, data.items["train"], cfg,
                                                val_items=data.items.get("val") or None,
                                                resume=args.resume)
    except MotionlangError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    model.config.lambdas = own
    model.save(out)
    last = history[-1] if history else {}
    print(f"{out}: epoch {last.get('epoch')}, train loss "
          f"{last.get('train', {}).get('loss', float('nan')):.4g}, "
          f"val loss {last.get('val', {}).get('loss', float('nan')):.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

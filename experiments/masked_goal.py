"""Teach a trained masked model where in-betweening gaps must arrive (``config.goal``).

    OMP_NUM_THREADS=2 .venv/bin/python experiments/masked_goal.py masked \\
        --splits experiments/state/masked/splits \\
        --data /tmp/corpus@1 --data bandai:../shared/data/bandai@1 --out runs/masked_goal \\
        --epochs 10 --lr 1e-4

MODEL (a run folder, a model file or a packaged name) gets a goal projection
(``models/masked/goal.py``), from zero, so training starts from the model as it is; then
its generator stage goes on with the run's training pairs, a fraction ``--goal`` of them
drawn as a gap to fill told where it ends, the rest as before, keeping the epoch of the
lowest validation loss. The tokenizer, and so the tokens, are unchanged. Writes
``OUT/model.pt`` with the run's ``splits/`` and licence beside it; then measure it with
``experiments/masked_inbetween.py`` (gaps) and ``evaluate-t2m --split val`` (plain
generation must not get worse). The data is read and checked as in
``experiments/masked_root_path.py``.
"""
from __future__ import annotations

import argparse
import dataclasses
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "experiments"))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("model", help="a masked run folder, model.pt or packaged name")
    p.add_argument("--data", action="append", required=True,
                   help="the model's sources with their weights, e.g. bandai:DIR@1")
    p.add_argument("--splits", help="the model's splits folder (default: MODEL/splits)")
    p.add_argument("--out", required=True)
    p.add_argument("--goal", type=float, default=0.5, help="fraction of pairs given a gap")
    p.add_argument("--epochs", type=int, default=10)
    p.add_argument("--batch", type=int, default=64)
    p.add_argument("--lr", type=float, default=1e-4)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--max-seconds", type=float, default=30.0)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--resume", action="store_true")
    args = p.parse_args()
    if not args.splits and not Path(args.model).exists():   # a packaged name
        sys.exit(f"{args.model}: a packaged model needs --splits (its run's splits folder)")

    import torch
    from masked_root_path import _load

    from motionlang.datasets.mixing import mix_training
    from motionlang.datasets.sources import parse_source
    from motionlang.models.masked.model import MaskedModel
    from motionlang.recipes.masked import _stage, generator_items
    from motionlang.training.config import TrainConfig

    torch.set_num_threads(args.threads)
    old, data = _load(args)
    config = dataclasses.replace(old.config, goal=args.goal)
    model = MaskedModel(config, old.features, old.text)
    missing, unexpected = model.load_state_dict(old.state_dict(), strict=False)
    if unexpected or missing != ["generator.goal.weight"]:
        sys.exit(f"unexpected weights: missing {missing}, unexpected {unexpected}")
    items = generator_items(model, data)
    sources = [parse_source(s) for s in args.data]
    train = mix_training(sources, items["train"], data.sources, args.seed)
    torch.manual_seed(args.seed)
    cfg = TrainConfig(out_dir=str(Path(args.out) / "generator"), epochs=args.epochs,
                      batch_size=args.batch, lr=args.lr, optimizer="adamw",
                      weight_decay=1e-5, grad_clip=1.0, seed=args.seed,
                      decay_epochs=args.epochs / 2)
    model = _stage(model, "generator", train, items.get("val") or [], cfg, args.resume,
                   lambda s: print(s, flush=True))
    run, out = Path(args.model), Path(args.out)
    run = Path(args.splits).parent if args.splits else run if run.is_dir() else run.parent
    found = {"splits": run / "splits", "LICENSE.txt": run / "LICENSE.txt"}
    for name, where in found.items():
        if where.exists() and not (out / name).exists():
            (shutil.copytree if where.is_dir() else shutil.copy2)(where, out / name)
    model.save(out / "model.pt")
    print(out / "model.pt")


if __name__ == "__main__":
    main()

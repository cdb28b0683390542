"""Does a masked model's tokenizer keep the root's path? And retrain its decoder so it does.

    # measure: test motions of each source through the tokens and back
    OMP_NUM_THREADS=2 .venv/bin/python experiments/masked_root_path.py measure \\
        experiments/state/masked --data /tmp/corpus --data bandai:../shared/data/bandai

    # retrain the decoder alone (encoder and codebooks frozen, so the tokens and the
    # generator trained on them stay valid) with the global-position loss
    OMP_NUM_THREADS=2 .venv/bin/python experiments/masked_root_path.py decoder \\
        experiments/state/masked --data /tmp/corpus --data bandai:../shared/data/bandai \\
        --out runs/masked_path --epochs 20

``measure`` decodes each test motion's rows, and the same rows through the tokenizer, to
global positions from the same start (``features.decode(..., pin_root=True)``) and prints,
per source, the mean root position error, the mean global joint error (mm), the body-frame
joint error (MPJPE, mm; what ``recipes.masked.tokenizer_report`` prints), the foot skating
through the tokens and of the motions themselves (m/s), and the motions' start-to-end
travel. The data is read, split and featurised as the model's run did (same
sources, seed and features; the split is checked against the run's ``splits/``).

``decoder`` trains the tokenizer's decoder alone (``MaskedModel`` stage ``"decoder"``) with
the frame, velocity, global-position and (``--foot``) foot-velocity losses on the run's training motions, keeping the
epoch of the lowest validation loss, and writes ``OUT/model.pt``: the same model with the
new decoder (and the run's ``splits/`` and licence beside it). Then ``measure`` it.
``half MODEL OUT`` stores a model file's weights in float16 (how the packaged
``masked.pt`` is kept). MODEL: a run folder, a model file or a packaged name.
"""
from __future__ import annotations

import argparse
import dataclasses
import shutil
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def _load(args: argparse.Namespace):
    """(model, TwoStreamData) of the run folder and sources."""
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.datasets.sources import parse_source
    from motionlang.datasets.splits import load_splits
    from motionlang.models.registry import load_model

    model = load_model(args.model, kind="masked").eval()   # a file, run folder or "masked"
    paths = [parse_source(s).path for s in args.data]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=args.seed,
                                max_seconds=args.max_seconds)
    run = Path(args.model)
    splits_dir = Path(args.splits) if args.splits else (
        run if run.is_dir() else run.parent) / "splits"
    if splits_dir.is_dir():
        saved = load_splits(splits_dir)
        for name, ids in saved.items():
            if sorted(map(str, ids)) != sorted(map(str, data.splits.get(name, []))):
                sys.exit(f"{splits_dir}: the {name} split differs from this data's "
                         "(other sources, seed or corpus?)")
    # the model's own features normalise: the rows are re-derived with them
    norm, mine = model.features.normalizer, data.features.normalizer
    if not (np.allclose(norm.mean, mine.mean) and np.allclose(norm.std, mine.std)):
        sys.exit("the model's features were fitted on other data than these sources")
    return model, data


def root_errors(model, rows: list[np.ndarray]) -> dict[str, float]:
    """Mean root, global-joint and body-frame joint errors (mm), and travel (m), of motions'
    rows (T, 66) through the tokenizer and back."""
    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.positions import local_joints
    feats, norm = model.features, model.features.normalizer
    out: dict[str, list[float]] = {"root_mm": [], "global_mm": [], "mpjpe_mm": [],
                                   "travel_m": [], "skate": [], "skate_real": []}
    for x in rows:
        back = model.reconstruct(x)
        truth, got = (feats.decode(r, (0.0, 0.0, 0.0), pin_root=True) for r in (x, back))
        out["root_mm"].append(1000 * float(np.linalg.norm(got[:, 0] - truth[:, 0], axis=-1)
                                           .mean()))
        out["global_mm"].append(1000 * float(np.linalg.norm(got - truth, axis=-1).mean()))
        local = [local_joints(norm.inverse(r.astype(np.float64))) for r in (x, back)]
        out["mpjpe_mm"].append(1000 * float(np.linalg.norm(local[0] - local[1], axis=-1)
                                            .mean()))
        out["skate"].append(foot_skating(got, model.fps))
        out["skate_real"].append(foot_skating(truth, model.fps))
        out["travel_m"].append(float(np.linalg.norm(truth[-1, 0, [0, 2]]
                                                    - truth[0, 0, [0, 2]])))
    return {k: float(np.nanmean(v)) for k, v in out.items()}


def measure(args: argparse.Namespace) -> None:
    model, data = _load(args)
    rng = np.random.default_rng(0)
    test = data.splits["test"]
    for source in sorted({data.sources[i] for i in test}):
        ids = [i for i in test if data.sources[i] == source]
        ids = [ids[k] for k in sorted(rng.choice(len(ids), min(args.limit, len(ids)),
                                                 replace=False))]
        r = root_errors(model, [data.sequences[i] for i in ids])
        print(f"{args.data[source]}: {len(ids)} test motions: root {r['root_mm']:.0f} mm, global joints "
              f"{r['global_mm']:.0f} mm, body-frame MPJPE {r['mpjpe_mm']:.1f} mm, foot "
              f"skating {r['skate']:.3f} m/s (the motions' own {r['skate_real']:.3f}), travel "
              f"{r['travel_m']:.2f} m", flush=True)


def decoder(args: argparse.Namespace) -> None:
    import torch

    from motionlang.recipes.masked import _stage
    from motionlang.training.config import TrainConfig
    torch.set_num_threads(args.threads)
    model, data = _load(args)
    model.config = dataclasses.replace(model.config, path=args.path, foot=args.foot)
    motions = {name: [{"motion": data.sequences[i]} for i in ids]
               for name, ids in data.splits.items()}
    cfg = TrainConfig(out_dir=str(Path(args.out) / "decoder"), epochs=args.epochs,
                      batch_size=args.batch, lr=args.lr, optimizer="adamw", grad_clip=1.0,
                      seed=args.seed, decay_epochs=args.epochs / 2)
    model = _stage(model, "decoder", motions["train"], motions.get("val") or [], cfg,
                   args.resume, lambda s: print(s, flush=True))
    model.set_stage("generator")
    run, out = Path(args.model), Path(args.out)
    run = run if run.is_dir() else run.parent
    found = {"splits": Path(args.splits) if args.splits else run / "splits",
             "LICENSE.txt": run / "LICENSE.txt"}
    for name, where in found.items():   # so that ``measure`` checks the split
        if where.exists() and not (out / name).exists():
            copy = shutil.copytree if where.is_dir() else shutil.copy2
            copy(where, out / name)
    model.save(out / "model.pt")
    print(out / "model.pt")


def half(args: argparse.Namespace) -> None:
    """The model file with its floating-point weights stored in float16 (half the size, for
    committed state; they load back into the float32 model)."""
    import torch

    from motionlang.utils.atomic import atomic_write
    state = torch.load(args.model, map_location="cpu", weights_only=False)
    state["state_dict"] = {k: v.half() if v.is_floating_point() else v
                           for k, v in state["state_dict"].items()}
    with atomic_write(args.out, "wb") as f:
        torch.save(state, f)
    print(args.out)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    for name in ("measure", "decoder"):
        a = sub.add_parser(name)
        a.add_argument("model", help="a masked run folder or model.pt")
        a.add_argument("--data", action="append", required=True)
        a.add_argument("--seed", type=int, default=0)
        a.add_argument("--max-seconds", type=float, default=30.0)
        a.add_argument("--limit", type=int, default=60, help="test motions per source")
        a.add_argument("--splits", help="the model's splits folder, checked against the "
                                        "data's (default: MODEL/splits where it exists)")
    d = sub.choices["decoder"]
    d.add_argument("--out", required=True)
    d.add_argument("--epochs", type=int, default=20)
    d.add_argument("--batch", type=int, default=64)
    d.add_argument("--lr", type=float, default=2e-4)
    d.add_argument("--path", type=float, default=1.0, help="weight of the path loss")
    d.add_argument("--foot", type=float, default=1.0, help="weight of the foot-velocity loss")
    d.add_argument("--threads", type=int, default=2)
    d.add_argument("--resume", action="store_true")
    h = sub.add_parser("half")
    h.add_argument("model", help="a model.pt")
    h.add_argument("out")
    args = p.parse_args()
    {"measure": measure, "decoder": decoder, "half": half}[args.cmd](args)


if __name__ == "__main__":
    main()

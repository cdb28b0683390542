"""Train the masked-token model's recipe on a machine that cannot read the data or run the
sentence encoder (a lent GPU machine: no network, no datasets, no MiniLM weights), in two
steps:

    # here: read the data, split it, fit the features, encode every caption once
    OMP_NUM_THREADS=1 .venv/bin/python experiments/masked_device.py pack \\
        --data /tmp/corpus@1 --data bandai:../shared/data/bandai@1 --out .pack RUN

    # there: both stages of ``recipes.masked`` on the pack, each in a wall-clock budget
    PYTHONPATH=src python3 experiments/masked_device.py train .pack RUN --device cuda \\
        --tokenizer-seconds 150 --generator-seconds 300

``pack`` writes, for the training and validation motions only, ``PACK/meta.pt`` (the fitted
features, splits, items and source of each motion), ``PACK/rows.xz`` (the normalised
12.5 Hz rows rounded to 1/500 of a unit, as time differences, xz-compressed: a tenth of
their size) and ``PACK/vectors.xz`` (each caption's MiniLM vector, as
``MaskedModel.sentence_vectors`` computes it, in float16), and starts the run folder ``RUN`` as ``train
masked`` does (splits, licence, commands.jsonl). ``train`` runs
``recipes.masked.train_stages`` on them: each stage first times one epoch of a throwaway
copy, then trains as many epochs as fit its budget (the second half decayed), keeping the
epoch of the lowest validation loss, as the recipe does. ``--split-mb N`` cuts the finished
``model.pt`` into parts of at most N MiB for a transfer that limits file sizes (``cat``
joins them).
"""
from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import lzma
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


class VectorTable:
    """A sentence encoder that only knows the captions it was given: ``many`` returns each
    caption's stored vector as a (1, D) token row (its mean is the vector)."""

    def __init__(self, vectors: dict):
        import torch
        self.vectors = {k: torch.as_tensor(v, dtype=torch.float32) for k, v in vectors.items()}
        self.dim = int(next(iter(self.vectors.values())).shape[-1])

    def many(self, sentences: list[str]) -> list:
        missing = [s for s in sentences if s not in self.vectors]
        if missing:
            raise KeyError(f"no stored vector for {missing[0]!r}")
        return [self.vectors[s][None] for s in sentences]


def _encode(captions: list[str]) -> dict:
    """Each caption's MiniLM vector (D,), as ``MaskedModel.sentence_vectors`` computes it
    (the default config's encoder and layer, token features mean-pooled), in batches."""
    from motionlang.models.masked.config import MaskedConfig
    from motionlang.models.text_tokens import TransformerTokens
    config = MaskedConfig()
    text = TransformerTokens(config.text_model, (config.text_layer,))
    vectors = {}
    for i in range(0, len(captions), 256):
        feats = text.many(captions[i:i + 256])
        vectors.update({c: f.mean(0).numpy() for c, f in zip(captions[i:i + 256], feats)})
    return vectors


def pack(args: argparse.Namespace) -> None:
    import torch

    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.datasets.sources import parse_source
    from motionlang.datasets.splits import save_splits
    from motionlang.training.run_log import log_command, write_licence

    sources = [parse_source(s) for s in args.data]
    started = time.perf_counter()
    paths = [s.path for s in sources]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=args.seed,
                                max_seconds=args.max_seconds)
    print(f"data: {len(data.sequences)} motions, {time.perf_counter() - started:.0f} s",
          flush=True)
    captions = sorted({str(it["sentence"]) for part in data.items.values() for it in part})
    vectors = _encode(captions)
    print(f"{len(captions)} caption vectors, {time.perf_counter() - started:.0f} s", flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    # only what training reads (the test motions stay here), small enough for a transfer
    # of limited size: the normalised rows rounded to 1/SCALE, as time differences, xz-packed
    used = [i for name in ("train", "val") for i in data.splits.get(name, [])]
    ids = sorted(set(used))
    rows = [np.clip(np.round(data.sequences[i] * args.scale), -32767, 32767).astype(np.int16)
            for i in ids]
    diffs = [np.concatenate([r[:1], np.diff(r, axis=0)]).T.ravel() for r in rows]
    (out / "rows.xz").write_bytes(lzma.compress(np.concatenate(diffs).tobytes()))
    kept = {str(it["sentence"]) for name in ("train", "val") for it in data.items.get(name, [])}
    names = sorted(kept)
    table = np.stack([vectors[c] for c in names]).astype(np.float16)   # 5e-4 relative
    (out / "vectors.xz").write_bytes(lzma.compress(table.tobytes()))
    torch.save({"features": data.features, "splits": {k: v for k, v in data.splits.items()
                                                      if k != "test"},
                "ids": ids, "lengths": [len(r) for r in rows], "dim": int(rows[0].shape[1]),
                "scale": args.scale, "captions": names,
                "items": {k: [{"sentence": it["sentence"], "id": it["id"]} for it in v]
                          for k, v in data.items.items() if k != "test"},
                "sources": data.sources, "source_args": [str(s) for s in sources]},
               out / "meta.pt")
    run = Path(args.run)
    save_splits(data.splits, run / "splits")
    write_licence(run, sources, "masked-token model")
    log_command(run / "commands.jsonl", {"model": "masked", "data": args.data,
                                         "packed_by": "experiments/masked_device.py"})
    for f in ("meta.pt", "rows.xz", "vectors.xz"):
        print(f"{out / f}: {(out / f).stat().st_size / 2**20:.1f} MiB")


def _vectors(p: Path, slim: dict) -> VectorTable:
    """The pack's caption vectors (stored in float16) as a sentence encoder."""
    table = np.frombuffer(lzma.decompress((p / "vectors.xz").read_bytes()), dtype=np.float16)
    table = table.reshape(len(slim["captions"]), -1)
    return VectorTable(dict(zip(slim["captions"], table.astype(np.float32))))


def _split(path: Path, mb: float) -> None:
    """``PATH.part0``, ``PATH.part1`` ... of at most ``mb`` MiB each (``cat`` joins them)."""
    blob, step = path.read_bytes(), int(mb * 2**20)
    for k in range(0, len(blob), step):
        path.with_name(f"{path.name}.part{k // step}").write_bytes(blob[k:k + step])


def _read_pack(p: Path, args: argparse.Namespace) -> tuple:
    """``(TwoStreamData, VectorTable, meta)`` of a pack (``--limit``: every k-th motion)."""
    import torch

    from motionlang.datasets.position_items import TwoStreamData
    slim = torch.load(p / "meta.pt", weights_only=False)
    flat = np.frombuffer(lzma.decompress((p / "rows.xz").read_bytes()), dtype=np.int16)
    sequences, at, F = {}, 0, slim["dim"]
    for i, n in zip(slim["ids"], slim["lengths"]):
        d = flat[at:at + n * F].reshape(F, n).T.astype(np.int32)
        sequences[i] = (np.cumsum(d, axis=0) / slim["scale"]).astype(np.float32)
        at += n * F
    text = _vectors(p, slim)
    splits = slim["splits"]
    if args.limit:   # a smoke test: every k-th motion of each split
        splits = {k: v[::max(1, len(v) // args.limit)] for k, v in splits.items()}
        sequences = {i: sequences[i] for v in splits.values() for i in v}
    items = {k: [{"motion": sequences[it["id"]], **it} for it in v if it["id"] in sequences]
             for k, v in slim["items"].items()}
    return TwoStreamData(slim["features"], splits, {}, sequences, items, slim["sources"]), \
        text, slim


def _epoch_seconds(model, stage: str, train: list, val: list, cfg) -> float:
    """Seconds of one epoch (validation and checkpoints included) of a throwaway copy: the
    second of two, since the first pays the device's start (CUDA's: several seconds)."""
    from motionlang.recipes.masked import _stage
    times = []
    for _ in range(2):
        with tempfile.TemporaryDirectory() as tmp:
            probe = dataclasses.replace(cfg, out_dir=tmp, epochs=1, decay_epochs=0.0)
            started = time.perf_counter()
            _stage(copy.deepcopy(model), stage, train, val, probe, False, lambda s: None)
            times.append(time.perf_counter() - started)
    return times[-1]


def train(args: argparse.Namespace) -> None:
    import torch

    from motionlang.datasets.sources import parse_source
    from motionlang.models.masked.config import MaskedConfig
    from motionlang.models.masked.model import MaskedModel
    from motionlang.recipes import masked as recipe
    from motionlang.training.config import TrainConfig

    started = time.perf_counter()
    data, text, slim = _read_pack(Path(args.pack), args)
    sequences, items = data.sequences, data.items
    sources = [parse_source(s) for s in slim["source_args"]]
    device = recipe.pick_device(args.device)
    if device == "cuda":
        torch.backends.cuda.matmul.allow_tf32 = False   # the float32 of a CPU run
    config = MaskedConfig(hidden=args.hidden, layers=args.layers, heads=args.heads)
    out = Path(args.run)
    log = print
    log(f"pack read: {len(sequences)} motions, {len(text.vectors)} captions, "
        f"{time.perf_counter() - started:.0f} s; device {device}")

    # the epochs that fit each budget, from one timed epoch of a throwaway copy
    data_cfg = recipe.MaskedTrainOptions(tokenizer_lr=args.tokenizer_lr,
                                         tokenizer_batch=args.tokenizer_batch, device=device)
    probe_model = MaskedModel(dataclasses.replace(
        config, n_features=data.features.dim, fps=data.features.fps, text_dim=text.dim),
        data.features, text).to(device)
    motions = {k: [{"motion": sequences[i]} for i in ids] for k, ids in data.splits.items()}
    tok_cfg = TrainConfig(epochs=1, batch_size=args.tokenizer_batch, lr=args.tokenizer_lr,
                          optimizer="adamw", weight_decay=1e-5, grad_clip=1.0, seed=args.seed)
    t_tok = _epoch_seconds(probe_model, "tokenizer", motions["train"], motions.get("val", []),
                           tok_cfg)
    tok_epochs = max(1, int(args.tokenizer_seconds / t_tok))
    log(f"tokenizer: {t_tok:.1f} s an epoch -> {tok_epochs} epochs")
    data_cfg = dataclasses.replace(data_cfg, tokenizer_epochs=tok_epochs)

    # the generator's epoch is timed inside train_stages' first call: a short first run
    # (1 epoch) gives the tokenizer and the time, the second continues to the budget
    gen_cfg = TrainConfig(epochs=1, batch_size=args.batch_size, lr=args.lr, optimizer="adamw",
                          weight_decay=1e-5, grad_clip=1.0, seed=args.seed)
    t0 = time.perf_counter()
    recipe.train_stages(data, text, sources, out, config, gen_cfg, data_cfg, resume=False,
                        device=device, log=log)
    t_gen = time.perf_counter() - t0
    log(f"stage 1 done in {t_gen:.0f} s")
    # time one generator epoch on the finished tokenizer, then train afresh to the budget
    model = MaskedModel.load(out / "tokenizer.pt", text_encoder=text).to(device)
    tokens = dict(zip(sequences, model.tokenize(list(sequences.values()))))
    gen_items = [{"tokens": tokens[it["id"]][:model.config.max_tokens],
                  "sentence": it["sentence"]} for it in items["train"]]
    val_items = [{"tokens": tokens[it["id"]][:model.config.max_tokens],
                  "sentence": it["sentence"]} for it in items.get("val", [])]
    t_epoch = _epoch_seconds(model, "generator", gen_items, val_items, gen_cfg)
    epochs = max(2, int(args.generator_seconds / t_epoch))
    log(f"generator: {t_epoch:.1f} s an epoch -> {epochs} epochs")
    shutil.rmtree(out / "generator")
    gen_cfg = dataclasses.replace(gen_cfg, epochs=epochs, decay_epochs=float(epochs // 2))
    path = recipe.train_stages(data, text, sources, out, config, gen_cfg, data_cfg,
                               resume=True, device=device, log=log)
    hist = out / "generator" / "history.json"
    summary = {"tokenizer_epoch_s": t_tok, "tokenizer_epochs": tok_epochs,
               "generator_epoch_s": t_epoch, "generator_epochs": epochs,
               "seconds": time.perf_counter() - started, "device": device,
               "gpu": torch.cuda.get_device_name() if device == "cuda" else None}
    (out / "device_summary.json").write_text(json.dumps(summary, indent=1))
    log(json.dumps(summary))
    if args.split_mb:
        _split(path, args.split_mb)
    log(f"{path} ({path.stat().st_size / 2**20:.1f} MiB); history {hist}")


def tokens(args: argparse.Namespace) -> None:
    """Here: the tokens of the pack's motions under a trained model's tokenizer
    (``PACK/tokens.pt``), so that ``more`` can train its generator further without rows."""
    import torch

    from motionlang.models.masked.model import MaskedModel
    args.limit = 0
    data, text, _ = _read_pack(Path(args.pack), args)
    model = MaskedModel.load(args.model, text_encoder=text)
    ids = list(data.sequences)
    toks = model.tokenize([data.sequences[i] for i in ids])
    torch.save({i: t.astype(np.int16) for i, t in zip(ids, toks)}, Path(args.pack) / "tokens.pt")


def more(args: argparse.Namespace) -> None:
    """There: the generator stage again, from a trained model's weights (a fresh optimiser,
    ``--epochs`` epochs, the second half decayed), on ``PACK/tokens.pt``; keeps the epoch of
    the lowest validation loss as the recipe does."""
    import torch

    from motionlang.datasets.mixing import mix_training
    from motionlang.datasets.sources import parse_source
    from motionlang.models.masked.model import MaskedModel
    from motionlang.recipes import masked as recipe
    from motionlang.training.config import TrainConfig

    p = Path(args.pack)
    slim = torch.load(p / "meta.pt", weights_only=False)
    text = _vectors(p, slim)
    toks = torch.load(p / "tokens.pt", weights_only=False)
    device = recipe.pick_device(args.device)
    model = MaskedModel.load(args.model, text_encoder=text)
    if args.fresh_hidden:   # the tokenizer kept, the token transformers new at this width
        torch.manual_seed(args.seed)
        fresh = MaskedModel(dataclasses.replace(model.config, hidden=args.fresh_hidden),
                            model.features, text)
        fresh.tokenizer.load_state_dict(model.tokenizer.state_dict())
        model = fresh
    model = model.to(device)
    n = model.config.max_tokens
    items = {k: [{"tokens": toks[it["id"]][:n].astype(np.int64), "sentence": it["sentence"],
                  "id": it["id"]} for it in v] for k, v in slim["items"].items()}
    sources = [parse_source(s) for s in slim["source_args"]]
    train_items = mix_training(sources, items["train"], slim["sources"], args.seed)
    out = Path(args.run)
    cfg = TrainConfig(epochs=args.epochs, batch_size=args.batch_size, lr=args.lr,
                      optimizer="adamw", weight_decay=1e-5, grad_clip=1.0, seed=args.seed,
                      decay_epochs=float(args.epochs // 2), out_dir=str(out / "generator"))
    started = time.perf_counter()
    model = recipe._stage(model, "generator", train_items, items.get("val") or [], cfg, False,
                          print)
    path = out / "model.pt"
    model.save(path)
    print(json.dumps({"epochs": args.epochs, "seconds": time.perf_counter() - started,
                      "device": device}))
    if args.split_mb:
        _split(path, args.split_mb)


def mirror(args: argparse.Namespace) -> None:
    """Here: a copy of the pack for ``more`` (no rows) whose training items also hold each
    training motion mirrored left/right (``build_twostream_data(mirror=True)``), tokenized by
    MODEL, under id ``"M" + id``, its sentences' sides swapped, their MiniLM vectors added."""
    import torch

    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.datasets.sources import parse_source
    from motionlang.models.masked.model import MaskedModel

    p, out = Path(args.pack), Path(args.out)
    slim = torch.load(p / "meta.pt", weights_only=False)
    sources = [parse_source(s) for s in slim["source_args"]]
    paths = [s.path for s in sources]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=args.seed,
                                max_seconds=args.max_seconds, mirror=True)
    if data.splits["train"] != slim["splits"]["train"]:
        sys.exit("mirror: the data's training split differs from the pack's")
    # the tokenizer reads rows normalised as the pack's were
    for a, b in ((data.features.normalizer.mean, slim["features"].normalizer.mean),
                 (data.features.normalizer.std, slim["features"].normalizer.std)):
        if not np.allclose(a, b, rtol=1e-5, atol=1e-6):
            sys.exit("mirror: the data's normaliser differs from the pack's")
    flipped = [it for it in data.items["train"] if it.get("mirrored")]
    motions = {}
    for it in flipped:
        motions.setdefault(it["id"], it["motion"])
    model = MaskedModel.load(args.model, text_encoder=_vectors(p, slim))
    ids = sorted(motions)
    toks = torch.load(p / "tokens.pt", weights_only=False)
    toks.update({"M" + i: t.astype(np.int16)
                 for i, t in zip(ids, model.tokenize([motions[i] for i in ids]))})
    old = _vectors(p, slim).vectors
    new = sorted({str(it["sentence"]) for it in flipped} - set(old))
    old.update(_encode(new))
    names = sorted(old)
    table = np.stack([np.asarray(old[c], dtype=np.float32) for c in names]).astype(np.float16)
    out.mkdir(parents=True, exist_ok=True)
    (out / "vectors.xz").write_bytes(lzma.compress(table.tobytes()))
    items = dict(slim["items"])
    items["train"] = items["train"] + [{"sentence": it["sentence"], "id": "M" + it["id"]}
                                       for it in flipped]
    srcs = dict(slim["sources"])
    srcs.update({"M" + i: srcs[i] for i in ids})
    torch.save({**slim, "captions": names, "items": items, "sources": srcs}, out / "meta.pt")
    torch.save(toks, out / "tokens.pt")
    print(f"{len(ids)} mirrored motions, {len(flipped)} items, {len(new)} new captions -> {out}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("pack")
    a.add_argument("run")
    a.add_argument("--data", action="append", required=True)
    a.add_argument("--out", default=".pack")
    a.add_argument("--seed", type=int, default=0)
    a.add_argument("--max-seconds", type=float, default=30.0)
    a.add_argument("--scale", type=float, default=500.0,
                   help="rows rounded to 1/SCALE of a normalised unit")
    b = sub.add_parser("train")
    b.add_argument("pack")
    b.add_argument("run")
    b.add_argument("--device", default="auto")
    b.add_argument("--tokenizer-seconds", type=float, default=150)
    b.add_argument("--generator-seconds", type=float, default=300)
    b.add_argument("--tokenizer-batch", type=int, default=128)
    b.add_argument("--tokenizer-lr", type=float, default=3e-4)
    b.add_argument("--batch-size", type=int, default=64)
    b.add_argument("--lr", type=float, default=2e-4)
    b.add_argument("--hidden", type=int, default=192)
    b.add_argument("--layers", type=int, default=4)
    b.add_argument("--heads", type=int, default=4)
    b.add_argument("--seed", type=int, default=0)
    b.add_argument("--split-mb", type=float, default=0)
    b.add_argument("--limit", type=int, default=0, help="smoke test: N motions a split")
    c = sub.add_parser("tokens")
    c.add_argument("pack")
    c.add_argument("model")
    d = sub.add_parser("more")
    d.add_argument("pack")
    d.add_argument("model")
    d.add_argument("run")
    d.add_argument("--device", default="auto")
    d.add_argument("--epochs", type=int, default=40)
    d.add_argument("--batch-size", type=int, default=64)
    d.add_argument("--lr", type=float, default=1e-4)
    d.add_argument("--seed", type=int, default=1)
    d.add_argument("--split-mb", type=float, default=0)
    d.add_argument("--fresh-hidden", type=int, default=0,
                   help="keep MODEL's tokenizer only: new token transformers this wide")
    e = sub.add_parser("mirror")
    e.add_argument("pack")
    e.add_argument("model")
    e.add_argument("--out", default=".packm")
    e.add_argument("--seed", type=int, default=0)
    e.add_argument("--max-seconds", type=float, default=30.0)
    args = ap.parse_args()
    {"pack": pack, "train": train, "tokens": tokens, "more": more,
     "mirror": mirror}[args.cmd](args)


if __name__ == "__main__":
    main()

"""The recipe of the masked-token model (``models.masked``), in two stages in one run folder:

1. **tokenizer** (``OUT/tokenizer/``): the VQ-VAE on random crops of the training motions
   (21-joint position rows, ``datasets.position_items``: split by motion, features fitted on
   the training motions, cached), the epoch of the lowest validation loss kept; then its
   reconstruction error in millimetres (MPJPE of the body-frame joints) and codebook use on
   the validation motions, and ``OUT/tokenizer.pt``.
2. **generator** (``OUT/generator/``): every motion tokenized once by the frozen tokenizer;
   the masked, residual and length models on (tokens, caption) pairs, the epoch of the
   lowest validation loss kept -> ``OUT/model.pt``, the licence file for non-commercial
   sources.

``--resume`` continues where the run stopped: a finished tokenizer (``tokenizer.pt``) is
not trained again; each stage's trainer resumes from its own ``last.pt``. The trainer
options (``--epochs``, ``--lr`` ...) are the generator stage's; the tokenizer stage has its
own (``--tokenizer-epochs`` ...). Torch-free until :func:`run` is called.
"""
from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motionlang.datasets.mixing import mix_training
from motionlang.datasets.position_items import build_twostream_data
from motionlang.datasets.text import tokenize
from motionlang.errors import MotionlangError
from motionlang.features.positions import local_joints
from motionlang.models.masked.config import MaskedConfig
from motionlang.models.registry import family
from motionlang.recipes import Recipe
from motionlang.training.run_log import lead_process
from motionlang.training.run_steps import begin_run
from motionlang.utils.checks import check_numbers

if TYPE_CHECKING:
    import numpy as np

    from motionlang.models.masked.model import MaskedModel
    from motionlang.training.config import TrainConfig

#: the model config fields the data decides, never the user
FROM_DATA = ("n_features", "fps", "text_dim")
RUN_FILES = ("tokenizer/ and generator/ (each stage's best.pt, last.pt, history.json), "
             "tokenizer.pt, splits/, LICENSE.txt for non-commercial data")
DEVICES = ("cpu", "cuda", "auto")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class MaskedTrainOptions:
    """The options of ``train masked`` that are neither the model's nor the trainer's."""

    max_seconds: float = _opt(30.0, "drop longer motions")
    tokenizer_epochs: int = _opt(30, "passes of the tokenizer stage over the training "
                                     "motions")
    tokenizer_lr: float = _opt(2e-4, "learning rate of the tokenizer stage")
    tokenizer_batch: int = _opt(64, "crops per step of the tokenizer stage")
    device: str = _opt("cpu", "where to train: cpu, cuda, or auto (cuda where available)",
                       choices=DEVICES)

    def __post_init__(self) -> None:
        check_numbers("MaskedTrainOptions", self, positive=("max_seconds", "tokenizer_lr"),
                      positive_ints=("tokenizer_epochs", "tokenizer_batch"))
        if self.device not in DEVICES:
            raise MotionlangError(f"device must be one of {', '.join(DEVICES)}, got "
                                  f"{self.device!r}")


def model_config(model_cfg: dict[str, Any]) -> Any:
    """The ``MaskedConfig`` of the user's fields, checked before any data is read; the
    fields the data decides are refused."""
    given = sorted(k for k in FROM_DATA if k in model_cfg)
    if given:
        raise MotionlangError(f"train masked: {', '.join(given)} come from the data, not "
                              "from options")
    return MaskedConfig(**{k: v for k, v in model_cfg.items() if v is not None})


def pick_device(name: str) -> str:
    """``cpu``, ``cuda`` or ``auto`` -> the torch device to train on."""
    import torch
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda" and not torch.cuda.is_available():
        raise MotionlangError("--device cuda: torch sees no CUDA device here")
    return name


def tokenizer_report(model: MaskedModel, rows: Sequence[np.ndarray]) -> dict[str, float]:
    """Reconstruction through the tokens of held-out motions: MPJPE in millimetres of the
    body-frame joints (every codebook, and the base codebook alone) and, per codebook, the
    fraction of its codes used and the perplexity of their use."""
    import numpy as np

    if model.features is None or model.features.normalizer is None:
        raise MotionlangError("tokenizer_report: the model has no fitted features")
    norm = model.features.normalizer
    errors: dict[int, list[float]] = {model.config.quantizers: [], 1: []}
    for x in rows:
        truth = local_joints(norm.inverse(np.asarray(x, dtype=np.float64)))
        for k in errors:
            back = local_joints(norm.inverse(model.reconstruct(x, k).astype(np.float64)))
            errors[k].append(float(np.linalg.norm(back - truth, axis=-1).mean()))
    out = {"mpjpe_mm": 1000 * float(np.mean(errors[model.config.quantizers])),
           "mpjpe_base_mm": 1000 * float(np.mean(errors[1]))}
    tokens = np.concatenate(model.tokenize(rows))
    for q in range(tokens.shape[1]):
        counts = np.bincount(tokens[:, q], minlength=model.config.codes)
        p = counts[counts > 0] / counts.sum()
        out[f"used_{q}"] = float((counts > 0).mean())
        out[f"perplexity_{q}"] = float(np.exp(-(p * np.log(p)).sum()))
    return out


def report_line(r: dict[str, float]) -> str:
    used = " ".join(f"{100 * v:.0f}%" for k, v in r.items() if k.startswith("used_"))
    return (f"MPJPE {r['mpjpe_mm']:.1f} mm (base codebook alone {r['mpjpe_base_mm']:.1f} "
            f"mm), codes used per codebook {used}")


def _stage(model: MaskedModel, stage: str, train: list, val: list, cfg: TrainConfig,
           resume: bool, log: Callable[[str], None]) -> MaskedModel:
    """Train one stage with the shared trainer into ``cfg.out_dir``; the model of its
    best epoch (the last one without validation items)."""
    from motionlang.models.masked.model import MaskedModel
    from motionlang.training.trainer import Trainer
    model.set_stage(stage)
    clock = [time.perf_counter()]

    def on_epoch(record: dict) -> None:
        now = time.perf_counter()
        seconds, clock[0] = now - clock[0], now
        if lead_process():
            terms = ", ".join(f"{k} {v:.3f}" for k, v in record["train"].items())
            val_loss = (record.get("val") or {}).get("loss")
            part = f", validation loss {val_loss:.3f}" if val_loss is not None else ""
            log(f"{stage} epoch {record['epoch']}/{cfg.epochs}: {terms}{part}, {seconds:.0f} s")

    Trainer(model, train, model.collate, cfg, val_set=val or None,
            on_epoch=on_epoch).fit(resume=resume and (Path(cfg.out_dir) / "last.pt").is_file())
    best = Path(cfg.out_dir) / "best.pt"
    if not best.is_file():
        return model.eval()
    device = model.device
    return MaskedModel.load(best, text_encoder=model.text).to(device).set_stage(stage).eval()


def run(sources: Sequence, out_dir: Path, model_cfg: dict[str, Any], train_cfg: TrainConfig,
        data_cfg: MaskedTrainOptions | None = None, *, resume: bool = False,
        options: dict | None = None, log: Callable[[str], None] = print) -> Path:
    """Train a masked model on ``sources`` (``datasets.sources.DataSource``) into the run
    folder ``out_dir`` (both stages, see module docstring); ``model_cfg``: ``MaskedConfig``
    fields; ``train_cfg``: the generator stage's trainer options (its seed also draws the
    split). Returns ``out_dir/model.pt``.

    Raises:
        MotionlangError: a bad option, ``resume`` with nothing to continue, weights on some
            sources only, unreadable data, no sentence encoder, no CUDA for ``cuda``.
    """

    from motionlang.models.text_tokens import TransformerTokens

    out = Path(out_dir)
    data_cfg = data_cfg if data_cfg is not None else MaskedTrainOptions()
    config = model_config(model_cfg)
    device = pick_device(data_cfg.device)
    done_tokenizer = out / "tokenizer.pt"
    if resume and not (done_tokenizer.is_file() or (out / "tokenizer" / "last.pt").is_file()):
        raise MotionlangError(f"--resume: nothing to continue in {out} (no tokenizer.pt or "
                              "tokenizer/last.pt)")
    text = TransformerTokens(config.text_model, (config.text_layer,))
    paths = [s.path for s in sources]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=train_cfg.seed,
                                max_seconds=data_cfg.max_seconds)
    lead = lead_process()
    note = begin_run(out, sources=sources, what="masked-token model", splits=data.splits,
                     resume=resume, options=options,
                     logged={"model": "masked", "data": [str(s) for s in sources],
                             "resume": resume, **config.to_dict(),
                             **dataclasses.asdict(data_cfg), **dataclasses.asdict(train_cfg)})
    started = time.perf_counter()
    captions = sorted({str(it["sentence"]) for part in data.items.values() for it in part})
    for i in range(0, len(captions), 256):   # every caption through the encoder once
        text.many(captions[i:i + 256])
    log(f"sentence vectors of {len(captions)} captions: {time.perf_counter() - started:.0f} s")
    path = train_stages(data, text, sources, out, config, train_cfg, data_cfg,
                        resume=resume, device=device, log=log)
    if lead and note:
        log(note.splitlines()[0])
    return path


def train_stages(data: Any, text: Any, sources: Sequence, out: Path, config: Any,
                 train_cfg: TrainConfig, data_cfg: MaskedTrainOptions, *, resume: bool,
                 device: str, log: Callable[[str], None] = print) -> Path:
    """Both stages of :func:`run` on prepared data: ``data`` a ``TwoStreamData``, ``text``
    the sentence encoder (anything with ``dim`` and ``many``, the captions' vectors already
    in it), ``config`` the user's ``MaskedConfig``; returns ``out/model.pt``."""
    import torch

    from motionlang.models.masked.model import MaskedModel

    out = Path(out)
    lead = lead_process()
    done_tokenizer = out / "tokenizer.pt"
    max_tokens = -(-round(data_cfg.max_seconds * data.features.fps) // 4)
    config = dataclasses.replace(config, n_features=data.features.dim, fps=data.features.fps,
                                 text_dim=int(text.dim),
                                 max_tokens=min(config.max_tokens, max_tokens))
    torch.manual_seed(train_cfg.seed)
    model = MaskedModel(config, data.features, text).to(device)
    log(f"masked: {len(data.splits['train'])} training motions, "
        f"{sum(p.numel() for p in model.parameters()):,} parameters, on {device}")
    motions = {name: [{"motion": data.sequences[i]} for i in ids]
               for name, ids in data.splits.items()}
    if done_tokenizer.is_file() and resume:
        model = MaskedModel.load(done_tokenizer, text_encoder=text).to(device)
        log(f"{done_tokenizer}: the tokenizer stage is done")
    else:
        tok_cfg = dataclasses.replace(train_cfg, out_dir=str(out / "tokenizer"),
                                      epochs=data_cfg.tokenizer_epochs,
                                      lr=data_cfg.tokenizer_lr,
                                      batch_size=data_cfg.tokenizer_batch, decay_epochs=0.0)
        model = _stage(model, "tokenizer", motions["train"], motions.get("val") or [],
                       tok_cfg, resume, log)
        held = [it["motion"] for it in motions.get("val") or motions["train"]]
        log("tokenizer on the validation motions: " + report_line(
            tokenizer_report(model, held)))
        if lead:
            model.save(done_tokenizer)
    items = generator_items(model, data)
    train_items = mix_training(sources, items["train"], data.sources, train_cfg.seed)
    gen_cfg = dataclasses.replace(train_cfg, out_dir=str(out / "generator"))
    model = _stage(model, "generator", train_items, items.get("val") or [], gen_cfg, resume,
                   log)
    # what `generate` reads to warn of an action the captions never named
    model.caption_words = sorted({w for it in data.items["train"]
                                  for w in tokenize(it["sentence"])})
    path = out / family("masked").model_file
    if lead:
        model.save(path)
        log(str(path))
    return path


def generator_items(model: Any, data: Any) -> dict[str, list[dict]]:
    """The generator stage's items of a ``TwoStreamData`` per split: ``{"tokens" (L, Q),
    "sentence", "id"}`` and, for a model that reads goals, the root's ``"track"`` (T, 3)
    (``models.masked.goal.root_track``) its gaps are measured on."""
    import numpy as np

    from motionlang.models.masked.goal import root_track

    cap = model.config.max_tokens
    tokens = dict(zip(data.sequences, model.tokenize(list(data.sequences.values()))))
    tracks = {}
    if model.generator.goal is not None:
        norm = model.features.normalizer
        tracks = {i: root_track(norm.inverse(np.asarray(rows, dtype=np.float64)))
                  for i, rows in data.sequences.items()}
    return {name: [{"tokens": tokens[it["id"]][:cap], "sentence": it["sentence"],
                    "id": it["id"], **({"track": tracks[it["id"]]} if tracks else {})}
                   for it in part] for name, part in data.items.items()}


MASKED = Recipe(run=run, data_config=MaskedTrainOptions,
                train_defaults={"epochs": 40, "batch_size": 64, "lr": 2e-4,
                                "optimizer": "adamw", "weight_decay": 1e-5,
                                "grad_clip": 1.0},
                run_files=RUN_FILES,
                resume_may_change=("tokenizer_epochs", "tokenizer_lr", "tokenizer_batch",
                                   "device"),
                extra_files=("tokenizer", "generator", "tokenizer.pt"),
                description="Two stages in one run folder: the tokenizer (its own "
                            "--tokenizer-* options), then the token transformers (the trainer "
                            "options). Each keeps the epoch of its lowest validation loss; "
                            "--resume continues either stage.")

"""The recipe of the text-motion retrieval model (``models.retrieval``): ``--data`` sources
-> (21-joint position rows, caption) pairs (``datasets.position_items``: split by motion,
features fitted on the training motions, cached) -> a ``RetrievalModel`` -> the shared
trainer, ``best.pt`` the epoch of the best validation retrieval (text -> motion R@1 + R@5
among the validation motions) -> ``model.pt``, its retrieval on the test split, the licence
file for non-commercial sources.

Several sources are mixed by their ``@W`` weights. The options are checked before the data
is read, and nothing is written before it is read. Torch-free until :func:`run` is called.
"""
from __future__ import annotations

import dataclasses
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motionlang.datasets.mixing import mix_training
from motionlang.datasets.position_items import build_twostream_data
from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.t2m import hit_ranks
from motionlang.evaluation.metrics.t2m import retrieval_scores as scores
from motionlang.models.registry import family, load_model
from motionlang.models.retrieval.config import RetrievalConfig
from motionlang.recipes import Recipe
from motionlang.training.run_log import lead_process
from motionlang.training.run_steps import begin_run, finish_run
from motionlang.utils.checks import check_numbers
from motionlang.utils.progress import progress

if TYPE_CHECKING:
    from motionlang.models.retrieval.model import RetrievalModel
    from motionlang.training.config import TrainConfig

#: alternative verbs of the Bandai captions' grammar (``datasets.bandai_text.CONTENTS``):
#: each names an action that other captions name in other words ("jogs" / "runs", "lifts" /
#: "raises", "makes a left turn" / "turns left"), so captions with them, left out of
#: training, measure how far the text side carries a wording it never trained on
HOLDOUT_WORDS = ("jogs", "lifts", "makes", "bearing", "sprints", "throws", "swings",
                 "gestures", "shouts")
#: the model config fields the data decides, never the user
FROM_DATA = ("n_features", "fps", "text_dim")
RUN_FILES = ("best.pt and last.pt (checkpoints), history.json, loss_curve.png, splits/, "
             "LICENSE.txt for non-commercial data")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class RetrievalOptions:
    """The options of ``train retrieval`` that are neither the model's nor the trainer's."""

    max_seconds: float = _opt(30.0, "drop longer motions")
    mirror: bool = _opt(False, "also train on every training motion mirrored left/right, its "
                               "captions' sides swapped")
    holdout_words: bool = _opt(False, "leave out of training every caption with one of the "
                                      "Bandai grammar's alternative verbs (jogs, lifts, ...); "
                                      "the validation captions with them are also scored on "
                                      "their own, and count in the choice of epoch")
    init: str | None = _opt(None, "fine-tune: start from this retrieval model (a packaged "
                                  "name such as 'retrieval', a file or a run folder), its "
                                  "sizes, text side and motion normaliser kept (the model "
                                  "options are then its own)", metavar="MODEL")

    def __post_init__(self) -> None:
        check_numbers("RetrievalOptions", self, positive=("max_seconds",))


def renormalise(items: Sequence[dict], fitted: Any, to: Any) -> None:
    """Items' ``motion`` rows, normalised by the features ``fitted`` on this data, normalised
    instead by ``to``'s (a fine-tuned model's own), in place; each motion once."""
    done: dict[int, Any] = {}
    seen: set[int] = set()   # an item listed twice (training and its split) is done once
    for it in items:
        if id(it) in seen:
            continue
        seen.add(id(it))
        key = id(it["motion"])
        if key not in done:
            done[key] = to.encode_rows(fitted.normalizer.inverse(it["motion"]))
        it["motion"] = done[key]


def model_config(model_cfg: dict[str, Any]) -> Any:
    """The ``RetrievalConfig`` of the user's fields (None: the default), checked before any
    data is read; the fields the data decides are refused."""
    given = sorted(k for k in FROM_DATA if k in model_cfg)
    if given:
        raise MotionlangError(f"train retrieval: {', '.join(given)} come from the data, not "
                              "from options")
    return RetrievalConfig(**{k: v for k, v in model_cfg.items() if v is not None})


def retrieval_set(items: Sequence[dict]) -> tuple[list[str], list, Any]:
    """Items ``{"motion", "sentence", "id"}`` -> (the captions, one per item; the motions,
    one per id in order of first appearance; hits (captions, motions) bool: True where the
    motion is the caption's own or has a caption equal to it, case and spacing aside)."""
    import numpy as np

    def key(s: str) -> str:
        return " ".join(s.lower().split())

    ids: dict[Any, int] = {}
    motions: list = []
    for it in items:
        if it["id"] not in ids:
            ids[it["id"]] = len(motions)
            motions.append(it["motion"])
    keys = [key(str(it["sentence"])) for it in items]
    owner = np.array([ids[it["id"]] for it in items], dtype=np.int64)
    hits = np.zeros((len(items), len(motions)), dtype=bool)
    hits[np.arange(len(items)), owner] = True
    by_key: dict[str, list[int]] = {}
    for i, k in enumerate(keys):
        by_key.setdefault(k, []).append(i)
    for rows in by_key.values():   # every caption of a key hits every motion of that key
        at = np.asarray(rows, dtype=np.int64)
        hits[np.ix_(at, np.unique(owner[at]))] = True
    return [str(it["sentence"]) for it in items], motions, hits


def uses_holdout(sentence: str) -> bool:
    """Whether a caption has a word of :data:`HOLDOUT_WORDS` (whole words, any case)."""
    return any(w in HOLDOUT_WORDS for w in re.findall(r"[a-z]+", sentence.lower()))


def scorer(items: Sequence[dict], holdout: bool = False
           ) -> Callable[[Any], dict[str, float]]:
    """A function ``model -> retrieval_scores`` (R@1/2/3/5/10, MedR, both directions) of
    ``items``' captions among their motions (:func:`retrieval_set`). ``holdout``: also the
    text -> motion scores of the captions with a held-out word (:func:`uses_holdout`),
    among the same motions, under ``holdout/``."""
    import numpy as np

    captions, motions, hits = retrieval_set(items)
    held = np.array([holdout and uses_holdout(c) for c in captions], dtype=bool)

    def score(model: Any) -> dict[str, float]:
        sims = np.asarray(model.embed_texts(captions) @ model.embed_motions(motions).T,
                          dtype=np.float64)
        out = scores(sims, hits)
        if held.any():   # text -> motion only: not every motion has such a caption
            ranks = hit_ranks(sims[held], hits[held])
            out.update({f"holdout/t2m/R{k:02d}": 100.0 * float(np.mean(ranks < k))
                        for k in (1, 2, 3, 5, 10)})
            out["holdout/t2m/MedR"] = float(np.median(ranks) + 1.0)
        return out
    return score


def train_on_items(train: Sequence[dict], val: Sequence[dict], model: RetrievalModel,
                   train_cfg: TrainConfig, *, resume: bool = False, holdout: bool = False,
                   log: Callable[[str], None] | None = print) -> RetrievalModel:
    """Train ``model`` on ``train`` into the run folder ``train_cfg.out_dir``; ``val`` picks
    the epoch (``best.pt``: the highest text -> motion R@1 + R@5, plus that of the captions
    with a held-out word where ``holdout``); without it the last epoch's weights are kept.
    ``log`` gets one line per epoch. Returns the model kept."""
    from motionlang.models.retrieval.model import RetrievalModel
    from motionlang.training.trainer import Trainer

    measured: dict[str, float] = {}
    score = scorer(val, holdout) if val else None

    def select(m: Any) -> float:   # lower is better
        assert score is not None
        measured.update(score(m))
        return -sum(measured.get(f"{p}t2m/R0{k}", 0.0) for p in ("", "holdout/")
                    for k in (1, 5))

    clock = [time.perf_counter()]

    def on_epoch(record: dict) -> None:
        now = time.perf_counter()
        seconds, clock[0] = now - clock[0], now
        if log is None or not lead_process():
            return
        part = (f"validation t2m R@1 {measured['t2m/R01']:.1f} %, R@5 "
                f"{measured['t2m/R05']:.1f} %, " if measured else "")
        if "holdout/t2m/R01" in measured:
            part += (f"held-out words R@1 {measured['holdout/t2m/R01']:.1f} %, R@5 "
                     f"{measured['holdout/t2m/R05']:.1f} %, ")
        log(f"epoch {record['epoch']}/{train_cfg.epochs}: {part}training loss "
            f"{record['train'].get('loss', float('nan')):.3f}, {seconds:.0f} s")

    trainer = Trainer(model, train, model.collate, train_cfg, val_set=list(val) or None,
                      select=select if val else None, on_epoch=on_epoch)
    trainer.fit(resume=resume)
    best = Path(train_cfg.out_dir) / "best.pt"
    if val and best.is_file():
        return RetrievalModel.load(best, text_encoder=model.text)
    return model.eval()


def run(sources: Sequence, out_dir: Path, model_cfg: dict[str, Any], train_cfg: TrainConfig,
        data_cfg: RetrievalOptions | None = None, *, resume: bool = False,
        options: dict | None = None) -> Path:
    """Train a retrieval model on ``sources`` (``datasets.sources.DataSource``) into the run
    folder ``out_dir``; ``model_cfg``: ``RetrievalConfig`` fields; ``train_cfg``: the
    shared trainer's (its seed also draws the split); ``options``: what to log in
    ``commands.jsonl`` (default: the configs). Returns ``out_dir/model.pt``.

    Raises:
        MotionlangError: a bad option, ``resume`` without a checkpoint, weights on some
            sources only, unreadable data, no sentence encoder.
    """
    import torch

    from motionlang.models.retrieval.model import RetrievalModel
    from motionlang.models.retrieval.text import (
        CHUNK,
        SentenceVectors,
        cache_file,
        sentence_vectors,
    )

    out = Path(out_dir)
    data_cfg = data_cfg if data_cfg is not None else RetrievalOptions()
    config = model_config(model_cfg)
    init = None
    if data_cfg.init is not None:   # before any data is read: a wrong model is one line
        init = load_model(data_cfg.init, kind="retrieval")
        config = init.config
    # before any data is read; captions are read as training reads them, queries later as
    # the trained model does (config.use_reading)
    text = SentenceVectors(init.text.tokens, reading=config.training_reading,
                           head=init.text.head) if init is not None else sentence_vectors(
        config.text_model, config.text_layer, config.training_reading)
    paths = [s.path for s in sources]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=train_cfg.seed,
                                max_seconds=data_cfg.max_seconds, mirror=data_cfg.mirror)
    train_items = mix_training(sources, data.items["train"], data.sources, train_cfg.seed)
    if data_cfg.holdout_words:
        train_items = [it for it in train_items if not uses_holdout(str(it["sentence"]))]
    lead = lead_process()
    note = begin_run(out, sources=sources, what="retrieval model", splits=data.splits,
                     resume=resume, options=options,
                     logged={"model": "retrieval", "data": [str(s) for s in sources],
                             "resume": resume, **config.to_dict(),
                             **dataclasses.asdict(data_cfg), **dataclasses.asdict(train_cfg)})
    # every caption through the frozen encoder once, in large batches, before training
    started = time.perf_counter()
    captions = sorted({str(it["sentence"]) for part in data.items.values() for it in part})
    kept = cache_file(config.text_model, config.text_layer)
    if lead:
        text.load(kept)
    bar = progress(total=len(captions), desc="sentence vectors", unit="captions",
                   disable=not lead)
    with bar:
        for i in range(0, len(captions), CHUNK):
            text.vectors(captions[i:i + CHUNK])
            bar.update(len(captions[i:i + CHUNK]))
    if lead:
        text.save(kept)
        print(f"sentence vectors of {len(captions)} captions: "
              f"{time.perf_counter() - started:.0f} s")
    torch.manual_seed(train_cfg.seed)
    if init is not None:
        model = init
        model.read_with(text)   # captions as training reads them, not as queries are read
        renormalise([*train_items, *(it for part in data.items.values() for it in part)],
                    data.features, init.features)
    else:
        config = dataclasses.replace(config, n_features=data.features.dim,
                                     fps=data.features.fps)
        model = RetrievalModel(config, data.features, text)
        model.fit_text(text.vectors(sorted({str(it["sentence"]) for it in train_items})))
    if lead:
        print(f"retrieval: {len(train_items)} training pairs ({len(data.splits['train'])} "
              f"motions), {sum(p.numel() for p in model.parameters()):,} parameters")
    model = train_on_items(train_items, data.items.get("val") or [], model, train_cfg,
                           resume=resume, holdout=data_cfg.holdout_words)
    path = out / family("retrieval").model_file

    def summary() -> str:
        line = f"{path}"
        test = data.items.get("test") or []
        if test:
            s = scorer(test, data_cfg.holdout_words)(model)
            line += (f": on {len(test)} test captions, text -> motion R@1 {s['t2m/R01']:.1f} "
                     f"%, R@5 {s['t2m/R05']:.1f} %, MedR {s['t2m/MedR']:g}")
            if "holdout/t2m/R01" in s:
                line += (f"; its captions with a held-out word R@1 "
                         f"{s['holdout/t2m/R01']:.1f} %, R@5 {s['holdout/t2m/R05']:.1f} %")
        return line

    return finish_run(path, model, summary, note)


RETRIEVAL = Recipe(run=run, data_config=RetrievalOptions,
                   train_defaults={"epochs": 20, "batch_size": 64, "lr": 3e-4,
                                   "optimizer": "adamw", "weight_decay": 1e-4,
                                   "grad_clip": 1.0},
                   run_files=RUN_FILES, resume_may_change=("mirror",),
                   description="Pairs of each motion with each of its captions; captions "
                               "that are the same, or near-duplicates, are not each other's "
                               "negatives. The kept epoch is the best validation text -> "
                               "motion R@1 + R@5.")

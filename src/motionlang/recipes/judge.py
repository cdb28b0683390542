"""The recipe of the real-motion judge (``models.judge``): the Bandai Namco takes
(``bandai:DIR``, split by the data's own rule) as labelled 21-joint motions
(``models.judge.fit``), with left/right mirrored copies and, if asked, a procedural corpus'
primitives -> a judge -> the shared trainer (random crops of ``JudgeConfig.window`` frames;
``best.pt`` is the epoch whose validation takes it names best) -> ``model.pt``, its accuracy
on the test takes, the licence file.

The Bandai Namco datasets are CC BY-NC 4.0 (``datasets.sources``): the judge and every
figure made with it are for non-commercial use only. Every option is checked before the
data is read, and nothing is written before it is read. Torch-free at import.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from motionlang.datasets.sources import LICENCE_FILE, DataSource, licence_text, parse_source
from motionlang.errors import MotionlangError
from motionlang.models.judge.config import JudgeConfig
from motionlang.models.registry import family
from motionlang.recipes import Recipe
from motionlang.training.run_log import lead_process
from motionlang.training.run_steps import begin_run, finish_run

if TYPE_CHECKING:
    from motionlang.models.judge.fit import JudgeItem
    from motionlang.models.judge.model import MotionJudge
    from motionlang.training.config import TrainConfig

#: what ``train judge`` and ``evaluate-judge`` say of the judge's terms (the Bandai data's)
NON_COMMERCIAL = (licence_text(DataSource("bandai", "DIR"), "judge") or "").splitlines()[0]
#: the model config fields the training data decides
DATA_FIELDS = ("contents", "styles", "n_features")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class JudgeOptions:
    """The options of ``train judge`` that are neither the model's nor the trainer's: what
    it trains on and the progress lines."""

    primitives: str | None = _opt(None, "also train on a procedural corpus' primitives that "
                                        "show a Bandai action (content only)",
                                  metavar="CORPUS")
    as_given: bool = _opt(False, "read motions on their own bodies (default: every motion "
                                 "laid on the training takes' median bone lengths, "
                                 "directions and gait kept, so a body's proportions do not "
                                 "pass for an action)")
    mirror: bool = _opt(True, "train without left/right mirrored copies of the takes")
    verbose: bool = _opt(False, "the training measures of every epoch (default: a short "
                                "line each)")


def check_model_options(model_cfg: dict[str, Any]) -> None:
    """The model options checked by :class:`JudgeConfig` itself, before any data is read;
    the label lists and the input size are the data's, not options."""
    given = sorted(set(DATA_FIELDS) & set(model_cfg))
    if given:
        raise MotionlangError(f"train judge: {', '.join(given)} come from the training data, "
                              "not from options")
    JudgeConfig(contents=["x"], styles=["x"], **model_cfg)


def train_on_items(train: Sequence[JudgeItem], val: Sequence[JudgeItem],
                   model_cfg: dict[str, Any], train_cfg: TrainConfig, *, mirror: bool = True,
                   uniform: bool = True, resume: bool = False, verbose: bool = False,
                   log: Callable[[str], None] | None = print
                   ) -> tuple[MotionJudge, list[dict]]:
    """Train a judge on labelled motions into the run folder ``train_cfg.out_dir``.

    train: its labels are every content and every known style there; with ``mirror`` each
        item's left/right mirrored copy joins it. val: whole motions that pick the epoch
        (mean of the content and style accuracy, ``models.judge.fit.accuracy``); none: the
        last epoch's weights.
    model_cfg: :class:`JudgeConfig` fields (sizes, ``bones``); with ``uniform`` and no
        ``bones``, the median bone lengths of ``train``.
    log: gets one line per epoch (``epoch N/M: validation content ..., style ..., S s``;
        with ``verbose`` the training measures too); None: silent.
    Returns the judge (eval mode) and the trainer's history.
    """
    import numpy as np
    import torch

    from motionlang.models.judge.fit import (
        accuracy,
        collate,
        examples,
        median_bones,
        mirror_item,
        new_judge,
    )
    from motionlang.models.judge.model import MotionJudge
    from motionlang.training.trainer import Trainer

    if not train:
        raise MotionlangError("no training items for the judge")
    cfg = dict(model_cfg)
    if uniform and cfg.get("bones") is None:
        cfg["bones"] = median_bones(train)
    items = list(train) + ([mirror_item(it) for it in train] if mirror else [])
    torch.manual_seed(train_cfg.seed)
    judge, train_set = new_judge(items, **cfg)
    scores: dict[str, float] = {}

    def select(model: torch.nn.Module) -> float:   # lower is better: minus the accuracy
        scores.update(accuracy(cast(MotionJudge, model), val))
        return -float(np.nanmean([scores["content"], scores["style"]]))

    clock = [time.perf_counter()]

    def on_epoch(record: dict) -> None:
        now = time.perf_counter()
        seconds, clock[0] = now - clock[0], now
        if log is None or not lead_process():
            return
        part = (f"validation content {scores['content']:.3f}, style {scores['style']:.3f}"
                if scores else "validation content -, style -")
        head = f"epoch {record['epoch']}/{train_cfg.epochs}: "
        if verbose:
            terms = " ".join(f"{k} {v:.3f}" for k, v in sorted(record["train"].items()))
            log(f"{head}{part}, {seconds:.1f} s; training crops: {terms}")
        else:
            log(f"{head}{part}, {seconds:.1f} s")

    trainer = Trainer(judge, train_set, collate, train_cfg,
                      val_set=examples(judge, val) or None, select=select if val else None,
                      on_epoch=on_epoch, length_of=lambda ex: len(ex["rows"]))
    history = trainer.fit(resume=resume)
    best = Path(train_cfg.out_dir) / "best.pt"
    final = MotionJudge.load(best) if val and best.exists() else judge
    return final.eval(), history


def run(sources: Sequence, out_dir: Path, model_cfg: dict[str, Any], train_cfg: TrainConfig,
        data_cfg: JudgeOptions | None = None, *, resume: bool = False,
        options: dict | None = None) -> Path:
    """Train a judge on the Bandai Namco takes ``sources[0]`` (``bandai:DIR``; a bare
    folder is read as one) into the run folder ``out_dir``: dataset 2's takes numbered
    0 mod 5 are test, 4 mod 5 validation, the rest and dataset 1 training
    (``datasets.bandai``). ``options``: what to log in ``commands.jsonl`` (default: the
    configs). Returns ``out_dir/model.pt``.

    Raises:
        MotionlangError: not one Bandai source, a bad option, no training takes, unreadable
            data.
    """
    import dataclasses

    from motionlang.models.judge.fit import accuracy, bandai_items, median_bones, primitive_items

    if len(sources) != 1:
        raise MotionlangError(f"train judge reads one bandai:DIR source, got {len(sources)}")
    source = parse_source(sources[0], kind="bandai")
    data_cfg = data_cfg if data_cfg is not None else JudgeOptions()
    check_model_options(model_cfg)
    out = Path(out_dir)
    train, val, test = (bandai_items(source.root, s) for s in ("train", "val", "test"))
    extra = primitive_items(data_cfg.primitives) if data_cfg.primitives else []
    if not train and not extra:
        raise MotionlangError(f"{source.root}: no Bandai training takes")
    used = [source] + ([data_cfg.primitives] if data_cfg.primitives else [])
    note = begin_run(out, sources=used, what="judge", resume=resume, options=options,
                     splits={"train": [it.id for it in train], "val": [it.id for it in val],
                             "test": [it.id for it in test]},
                     logged={"model": "judge", "data": str(source), "resume": resume,
                             **model_cfg, **dataclasses.asdict(data_cfg),
                             **dataclasses.asdict(train_cfg)})
    print(f"judge: {len(train)} training takes, {len(val)} validation, {len(test)} test"
          + (f"; {len(extra)} procedural primitives" if data_cfg.primitives else ""))
    cfg = dict(model_cfg)
    if not data_cfg.as_given and cfg.get("bones") is None:
        cfg["bones"] = median_bones(train or extra)   # the real actors' body, not the corpus'
    judge, _ = train_on_items(train + extra, val, cfg, train_cfg, mirror=data_cfg.mirror,
                              uniform=not data_cfg.as_given, resume=resume,
                              verbose=data_cfg.verbose)
    path = out / family("judge").model_file

    def summary() -> str:
        line = f"{path}: {len(judge.config.contents)} contents, {len(judge.config.styles)} styles"
        if test:
            acc = accuracy(judge, test)
            line += (f"; on the {acc['n']} test takes content {acc['content']:.3f}, style "
                     f"{acc['style']:.3f}")
        return line

    return finish_run(path, judge, summary, note)


JUDGE = Recipe(run=run, data_config=JudgeOptions,
               train_defaults={"epochs": 30, "batch_size": 32, "lr": 1e-3,
                               "optimizer": "adamw", "weight_decay": 1e-4},
               several_sources=False, source_kind="bandai", resume_may_change=("verbose",),
               run_files=f"best.pt and last.pt (checkpoints), history.json, loss_curve.png, "
                         f"splits/ (the takes of each split), {LICENCE_FILE} (the "
                         f"non-commercial licence)",
               description=f"{NON_COMMERCIAL} Splits: dataset 2's takes numbered 0 mod 5 are "
                           "test, 4 mod 5 validation (picks the epoch), the rest and dataset 1 "
                           "training.")

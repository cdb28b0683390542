"""The recipe of the two-stream text-to-motion model (Ghosh et al. 2021): ``--data`` sources
-> (motion, sentence) items on the 21-joint positions (``datasets.position_items``) -> a
``TwoStreamModel`` (the full model or one of the paper's ablations) -> the shared trainer
with annealed teacher forcing (``recipes.twostream_train``) -> ``model.pt``.

The model file holds the final weights, unless ``--select-evaluator`` scores every epoch's
motions on validation pairs (``evaluation.t2m.selection``): then it holds the epoch with the
highest R-precision (``best.pt``). The loss does not choose: it includes the discriminator's
own term, early epochs are still teacher-forced, and it keeps falling while the motions made
from sentences get worse. The "no-joint-training" ablation trains in two stages, each with its own
checkpoints in ``OUT/pose`` and ``OUT/text``. Several sources are mixed by their ``@W``
weights; a run trained on a non-commercial source gets the licence file. The options are
checked before the data preparation, and nothing is written before the data is read.
Torch-free until :func:`run` is called.
"""
from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.datasets.mixing import mix_training
from motionlang.datasets.position_items import build_twostream_data
from motionlang.errors import MotionlangError
from motionlang.evaluation.t2m.selection import format_scores, guo_selector
from motionlang.models.length import SentenceLength
from motionlang.models.registry import family
from motionlang.models.twostream.config import ABLATIONS
from motionlang.recipes import Recipe
from motionlang.training.run_log import lead_process
from motionlang.training.run_steps import begin_run, finish_run
from motionlang.utils.checks import check_numbers

#: what a run folder holds besides the model and commands.jsonl
RUN_FILES = ("best.pt and last.pt (checkpoints; in pose/ and text/ for the two-stage "
             "ablation), history.json, loss_curve.png, splits/")


#: how several sources' motions are normalised (``TwoStreamOptions.normalise``)
NORMALISE = ("together", "by-source")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class TwoStreamOptions:
    """The options of ``train twostream`` that are neither the model's nor the trainer's:
    the ablation, the teacher-forcing schedule and the data."""

    ablation: str = _opt("full", "the full model or one of the paper's ablations",
                         choices=tuple(ABLATIONS))
    forcing_steps: int = _opt(200, "optimiser steps over which teacher forcing anneals 1 -> 0")
    max_frames: int | None = _opt(None, "crop sequences to this many 12.5 Hz frames")
    max_seconds: float = _opt(30.0, "drop longer motions")
    mirror: bool = _opt(False, "also train on every training motion mirrored left/right, its "
                               "sentences' sides swapped (beyond the paper)")
    select_evaluator: str | None = _opt(
        None, "a text-motion evaluator (file, run folder or packaged name): keep the epoch "
              "whose motions have the highest validation R-precision top-3 under it")
    select_data: str | None = _opt(
        None, "the source whose validation pairs --select-evaluator scores (default: the "
              "only --data source)")
    select_pairs: int = _opt(256, "how many validation pairs to score each epoch (0: all)")
    normalise: str = _opt("together", "several --data sources: fit the feature normaliser on "
                                      "their training motions together, or on each source's "
                                      "own (by-source: each fills the model's range as it "
                                      "would alone, and each sentence's motion comes out in "
                                      "the statistics of the source it reads like; beyond "
                                      "the paper)",
                          choices=NORMALISE)
    output_source: int = _opt(-1, "with --normalise by-source: the --data source whose "
                                  "normaliser the model's features keep, for the motions it "
                                  "reads (0 the first, -1 the last)")

    def __post_init__(self) -> None:
        check_numbers("TwoStreamOptions", self, positive_ints=("max_frames",),
                      nonneg_ints=("forcing_steps", "select_pairs"), positive=("max_seconds",))
        if self.select_data and not self.select_evaluator:
            raise MotionlangError("TwoStreamOptions.select_data needs "
                                  "TwoStreamOptions.select_evaluator")
        if self.normalise not in NORMALISE:
            raise MotionlangError(f"TwoStreamOptions.normalise must be one of "
                                  f"{', '.join(NORMALISE)}, got {self.normalise!r}")
        if self.ablation not in ABLATIONS:
            raise MotionlangError(f"TwoStreamOptions.ablation must be one of "
                                  f"{', '.join(ABLATIONS)}, got {self.ablation!r}")


def model_config(model_cfg: dict[str, Any], ablation: str = "full") -> Any:
    """The ``TwoStreamConfig`` of the user's fields (None: the config's default) with the
    ablation's flags; checked by the config."""
    from motionlang.recipes.twostream_train import make_config
    return make_config(ablation, **{k: v for k, v in model_cfg.items() if v is not None})


def summary(path: Path, history: list[dict]) -> str:
    """One line for a finished run: the model file, its epoch (the selected one, with its
    validation scores, where epochs were scored; else the last) and losses."""
    chosen = next((h for h in history if h.get("selected")), None)
    last = chosen or (history[-1] if history else {})
    scores = format_scores(last.get("val") or {})
    return (f"{path}: epoch {last.get('epoch')}{' (selected: ' + scores + ')' if chosen else ''}"
            f", train loss {last.get('train', {}).get('loss', float('nan')):.4g}, "
            f"val loss {last.get('val', {}).get('loss', float('nan')):.4g}")


def output_source(sources: Sequence, data_cfg: TwoStreamOptions) -> int | None:
    """The index of the source whose normaliser the model keeps (None: one normaliser for
    all), checked against the sources before the data is read."""
    if data_cfg.normalise != "by-source":
        return None
    n = len(sources)
    if n < 2:
        raise MotionlangError("--normalise by-source needs several --data sources")
    if not -n <= data_cfg.output_source < n:
        raise MotionlangError(f"--output-source {data_cfg.output_source}: there are {n} "
                              f"--data sources (0 to {n - 1}, or -1 for the last)")
    return data_cfg.output_source


def selection_source(sources: Sequence, data_cfg: TwoStreamOptions) -> str | None:
    """The data source whose validation pairs pick the epoch (None: no selection)."""
    if not data_cfg.select_evaluator:
        return None
    if data_cfg.select_data:
        return data_cfg.select_data
    if len(sources) != 1:
        raise MotionlangError("--select-evaluator with several --data sources needs "
                              "--select-data: the source whose validation pairs it scores")
    return str(sources[0].path)


def run(sources: Sequence, out_dir: Path, model_cfg: dict[str, Any], train_cfg,
        data_cfg: TwoStreamOptions | None = None, *, resume: bool = False,
        options: dict | None = None) -> Path:
    """Train a two-stream model on ``sources`` (``datasets.sources.DataSource``) into the run
    folder ``out_dir``; ``model_cfg``: ``TwoStreamConfig`` fields; ``train_cfg``: the
    shared trainer's ``TrainConfig`` (its seed also draws the split); ``options``: what to
    log in ``commands.jsonl`` (default: the configs). Returns ``out_dir/model.pt`` (written
    by the lead process under torchrun).

    Raises:
        MotionlangError: a bad config value, ``resume`` without a checkpoint, weights on
            some sources only, unreadable data.
    """
    import numpy as np
    import torch

    from motionlang.models.twostream.model import TwoStreamModel
    from motionlang.models.twostream.sources import fit_source_output
    from motionlang.models.twostream.start import fit_start_pose
    from motionlang.recipes.twostream_train import ForcingSchedule, train_twostream

    out = Path(out_dir)
    data_cfg = data_cfg if data_cfg is not None else TwoStreamOptions()
    config = model_config(model_cfg, data_cfg.ablation)   # checked before the data is read
    by_source = output_source(sources, data_cfg)
    select = None
    scored = selection_source(sources, data_cfg)
    if scored is not None:   # its evaluator and data read before the long data preparation
        select = guo_selector(data_cfg.select_evaluator, scored, pairs=data_cfg.select_pairs,
                              seed=train_cfg.seed, max_seconds=data_cfg.max_seconds)
    # one line per epoch from the trainer (the progress bar only shows on a terminal)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    lead = lead_process()   # under torchrun only rank 0 writes files and prints
    paths = [s.path for s in sources]
    data = build_twostream_data(paths if len(paths) > 1 else paths[0], seed=train_cfg.seed,
                                max_seconds=data_cfg.max_seconds,
                                max_frames=data_cfg.max_frames, mirror=data_cfg.mirror,
                                by_source=by_source)
    train_items = mix_training(sources, data.items["train"], data.sources, train_cfg.seed)
    note = begin_run(out, sources=sources, what="two-stream model", splits=data.splits,
                     resume=resume, options=options,
                     logged={"model": "twostream", "data": [str(s) for s in sources],
                             "resume": resume, **config.to_dict(), **vars(data_cfg),
                             **vars(train_cfg)})
    torch.manual_seed(train_cfg.seed)
    model = TwoStreamModel(config, data.features.normalizer)
    model.length_model = SentenceLength.from_items(data.items["train"])
    # every sentence's token features once, in a fixed order (the same numbers on a resume)
    model.text_encoder.prepare([it["sentence"] for items in (train_items,
                                data.items.get("val") or []) for it in items])
    if lead:
        print(f"twostream ({data_cfg.ablation}): {len(data.items['train'])} training pairs "
              f"({len(data.splits['train'])} motions), "
              f"{sum(p.numel() for p in model.parameters()):,} parameters")
    own = [it for it in data.items["train"] if not it.get("mirrored")]

    def fit_heads(model) -> None:
        """The first pose read from the sentence, and by source each sentence's source,
        fitted on ``model`` as it stands: what its generation uses."""
        model.start_pose = fit_start_pose(model, [it["sentence"] for it in own],
                                          np.stack([it["motion"][0] for it in own]),
                                          seed=train_cfg.seed)
        if by_source is not None:
            model.sources = fit_source_output(model, [it["sentence"] for it in own],
                                              [data.sources.get(it["id"], 0) for it in own],
                                              data.normalizers, seed=train_cfg.seed)

    model, history = train_twostream(
        model, train_items, train_cfg, val_items=data.items.get("val") or None,
        first_frames=data.first_frames(), resume=resume,
        schedule=ForcingSchedule(1.0, 0.0, data_cfg.forcing_steps),
        select=None if select is None else WithHeads(select, fit_heads))
    fit_heads(model)   # on the kept epoch's weights
    path = out / family("twostream").model_file
    return finish_run(path, model, lambda: summary(path, history), note)


@dataclass
class WithHeads:
    """A ``select`` that scores each epoch's model as it will generate: ``fit`` (its first
    pose and sources read from the sentence) first, then ``select``."""

    select: Callable[[Any], dict[str, float]]
    fit: Callable[[Any], None]

    def __call__(self, model) -> dict[str, float]:
        self.fit(model)
        return self.select(model)

    @property
    def key(self) -> str:
        # another key from the bare selector's: a resumed run does not rank its epochs
        # against scores made without the fitted first pose
        return f"{getattr(self.select, 'key', 'select')}, with its first pose fitted"


TWOSTREAM = Recipe(run=run, data_config=TwoStreamOptions,
                   train_defaults={"epochs": 20, "batch_size": 32, "grad_clip": 5.0},
                   run_files=RUN_FILES, resume_may_change=("forcing_steps", "mirror", "select_evaluator",
                                                    "select_data", "select_pairs"),
                   extra_files=("pose", "text"))

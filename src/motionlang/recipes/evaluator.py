"""The recipe of the text-motion evaluator (Guo et al. 2022): one ``--data`` source -> its
motions as HumanML3D rows of one body and its tagged captions
(``datasets.evaluator_items.build_evaluator_data``) -> a ``TextMotionEvaluator`` -> the
shared trainer -> ``model.pt``, the epoch of the best validation R-precision.

The model's sizes and loss are ``EvaluatorConfig`` fields; the recipe sets what the data
decides (the rows' size, the foot-contact columns left out, the bones every motion is laid
on). Every option is checked before the data is read, and nothing is written before it is
read. Importing this module does not import torch.
"""
from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motionlang.datasets.evaluator_items import build_evaluator_data
from motionlang.errors import MotionlangError
from motionlang.evaluation.t2m.yardstick import r_precision_miss
from motionlang.features.h3d_vectors import H3D_BODIES
from motionlang.models.evaluator.config import EvaluatorConfig
from motionlang.models.registry import family
from motionlang.recipes import Recipe
from motionlang.training.run_log import lead_process
from motionlang.training.run_steps import begin_run, finish_run
from motionlang.utils.checks import check_numbers

#: the HumanML3D bodies the rows can be made on (``features.h3d_vectors.H3D_BODIES``)
BODIES = ("kit", "smpl")
#: config fields the recipe sets from the data, never the user
FROM_DATA = ("motion_dim", "drop_last", "bones")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class EvaluatorDataOptions:
    """The data options of ``train evaluator`` (the recipe's, not the model's)."""

    body: str = _opt("kit", "the rows' body: kit = 21 joints at 12.5 fps, 251 values (any "
                            "rig); smpl = 22 SMPL joints at 20 fps, 263 values (rigs with "
                            "SMPL joints)", choices=BODIES, aliases=("--data-body",))
    as_given: bool = _opt(False, "kit body: make each motion's rows on its own bones "
                                 "(default: every motion laid on the training motions' "
                                 "median bone lengths, as the public pipeline retargets to "
                                 "one subject, so that a body's proportions do not pass for "
                                 "what it does)")
    max_seconds: float = _opt(30.0, "drop longer motions")

    def __post_init__(self) -> None:
        check_numbers("EvaluatorDataOptions", self, positive=("max_seconds",))
        if self.body not in BODIES:
            raise MotionlangError(f"EvaluatorDataOptions.body must be one of "
                                  f"{', '.join(BODIES)}, got {self.body!r}")


def model_config(model_cfg: dict[str, Any], body: str):
    """The ``EvaluatorConfig`` of the user's fields on ``body``'s rows (the 4 foot-contact
    columns left out, as the public evaluator), checked by the config itself."""
    given = [k for k in FROM_DATA if k in model_cfg]
    if given:
        raise MotionlangError(f"train evaluator: {', '.join(given)} come from the data, not "
                              "an option")
    return EvaluatorConfig(motion_dim=H3D_BODIES[body].dim, drop_last=4, **model_cfg)


def _resumed_bones(out: Path) -> list[float] | None:
    """The bones of the run being resumed: its normaliser and weights were fitted on them."""
    from motionlang.training.run_files import check_resume, read_training_checkpoint
    ck = read_training_checkpoint(check_resume(out, read=False))
    return ck["model"]["config"].get("bones")


def _kept_epoch(history: list[dict], with_val: bool) -> str:
    """One line on the epoch saved: the best validation score (R-precision, else the
    loss), else the last."""
    scored = [h for h in history if h.get("val")]
    key = "select" if scored and "select" in scored[-1]["val"] else "loss"
    kept = min(scored, key=lambda h: h["val"][key]) if with_val and scored else \
        (history[-1] if history else {})
    v = kept.get("val", {})
    return (f"epoch {kept.get('epoch')}, train loss "
            f"{kept.get('train', {}).get('loss', float('nan')):.4g}, val loss "
            f"{v.get('loss', float('nan')):.4g}"
            + (f", val R-precision top-3 {1 - v['select']:.3f}" if "select" in v else ""))


def run(sources: Sequence, out_dir: Path, model_cfg: dict[str, Any], train_cfg,
        data_cfg: EvaluatorDataOptions | None = None, *, resume: bool = False,
        options: dict | None = None) -> Path:
    """Train an evaluator on the one source ``sources[0]`` into the run folder ``out_dir``;
    ``model_cfg``: ``EvaluatorConfig`` fields; ``train_cfg``: a ``TrainConfig`` (its
    optimiser is Adam, the public code's); ``options``: what to log in ``commands.jsonl``
    (default: the configs). Returns ``out_dir/model.pt``.

    Raises:
        MotionlangError: not one source, a bad config value, ``resume`` without a run to
            resume, unreadable data.
    """
    import torch

    from motionlang.models.evaluator.model import TextMotionEvaluator
    from motionlang.recipes.evaluator_train import train_evaluator

    if len(sources) != 1:
        raise MotionlangError(f"train evaluator reads one dataset, got {len(sources)}")
    data_cfg = data_cfg if data_cfg is not None else EvaluatorDataOptions()
    out, body = Path(out_dir), data_cfg.body
    cfg = dataclasses.replace(train_cfg, optimizer="adam")
    config = model_config(model_cfg, body)   # checked before the data is read
    # every motion on one body (the training motions' median bones) unless as_given; a
    # resumed run keeps the body it started on
    bones = _resumed_bones(out) if resume else (
        "median" if not data_cfg.as_given and body == "kit" else None)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    lead = lead_process()
    data = build_evaluator_data(str(sources[0]), body, seed=cfg.seed,
                                max_seconds=data_cfg.max_seconds, bones=bones)
    config.bones = data.bones
    note = begin_run(out, sources=sources, what="evaluator", resume=resume, options=options,
                     splits={s: list(dict.fromkeys(it["id"] for it in items))
                             for s, items in data.items.items()},
                     logged={"model": "evaluator", "data": [str(s) for s in sources],
                             "resume": resume, **model_cfg, **vars(data_cfg), **vars(cfg)})
    torch.manual_seed(cfg.seed)
    model = TextMotionEvaluator(config)
    if lead:
        print(f"evaluator ({body} body, {config.motion_dim} values a frame): "
              f"{len(data.items['train'])} training captions, "
              f"{sum(p.numel() for p in model.parameters()):,} parameters")
    val = data.items.get("val") or None
    # the epoch kept: the best validation R-precision top-3 (one caption per motion, batches
    # of 32), what the evaluator is for; the contrastive loss follows it badly where
    # captions repeat (templated captions). Fewer than 32 validation motions: the loss.
    select = r_precision_miss(val, seed=cfg.seed) if val else None
    model, history = train_evaluator(model, data.items["train"], cfg, val_items=val,
                                     body=body, resume=resume, select=select)
    path = out / family("evaluator").model_file
    if lead and val and (out / "best.pt").is_file():
        model = TextMotionEvaluator.load(out / "best.pt")
    return finish_run(path, model, lambda: f"{path}: {_kept_epoch(history, bool(val))}",
                      note)


EVALUATOR = Recipe(run=run, data_config=EvaluatorDataOptions, several_sources=False,
                   resume_may_change=("as_given",),   # a resume keeps the run's body
                   train_defaults={"epochs": 30, "batch_size": 32, "grad_clip": 0.5})

"""Choosing a text-to-motion model's epoch by what the field measures: the R-precision of its
motions under a text-motion evaluator (Guo et al. 2022), on validation pairs.

A generator's training loss is a poor guide to that. The two-stream model's losses keep
falling while the motions it makes from sentences drift towards one another
(``docs/results/twostream.md``, Choosing the epoch), so a recipe that keeps the epoch of the
lowest loss keeps a worse model. :func:`guo_selector` makes the trainer's ``select``
(``training.trainer.Trainer``): every epoch the model generates one motion for each of a
fixed set of validation captions, and the epoch with the highest top-3 R-precision is kept
(FID and diversity are recorded beside it).
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from motionlang.evaluation.t2m.guo import GuoOptions, GuoRun, load_evaluator, model_specs
from motionlang.evaluation.t2m.yardstick import generated_rows, guo_metrics

#: the measures a selector reports each epoch (validation record keys)
TOP3, FID, DIVERSITY = "R-precision top-3", "FID", "Diversity"


def guo_selector(evaluator: Any, data: str | Path, *, split: str = "val", pairs: int = 256,
                 seed: int = 0, repeats: int = 5, batch_size: int = 32,
                 max_seconds: float | None = 30.0) -> Callable[[Any], dict[str, float]]:
    """A ``select`` for the shared trainer: model -> ``{"select": -top-3, TOP3, FID, DIVERSITY}``.

    Args:
        evaluator: a text-motion evaluator, or its file, run folder or packaged name
            (``evaluation.t2m.guo.load_evaluator``).
        data: the data source whose ``split`` pairs are scored (anything
            ``datasets.evaluator_items.build_evaluator_data`` reads, e.g.
            ``bandai:DIR``), read on the evaluator's body; one caption per motion.
        pairs: how many of them (drawn with ``seed``, spread evenly over the split's
            order; 0: all).
        repeats, batch_size: R-precision is the mean over ``repeats`` shuffles into batches
            of ``batch_size`` (the field's 32).
        max_seconds: longer motions are left out, as the training data leaves them out (a
            randomly split source splits the motions it keeps).

    The motions are generated at the real motions' lengths with the model's defaults and
    ``seed``; FID is against the same real motions. The data is read once, here. The
    function's ``key`` names what it scores, on what: the trainer does not compare its
    scores with another selector's.

    Raises:
        MotionlangError: an unreadable evaluator or data, an SMPL-body evaluator (the
            models make 21-joint motions), fewer pairs than a batch.
    """
    ev = evaluator if hasattr(evaluator, "embed_motions") else load_evaluator(evaluator)
    model_specs(ev, ["the model"])   # a kit-body evaluator, or one line saying why not
    run = GuoRun.prepare(ev, data, split=split, seed=seed, limit=pairs, max_seconds=max_seconds,
                         options=GuoOptions(rp_batch=batch_size))
    captions = [p["caption"] for p in run.pairs]
    frames = [len(p["motion"]) + 1 for p in run.pairs]   # rows are steps between frames
    text = ev.embed_texts(captions, [p.get("tokens") for p in run.pairs])
    real = ev.embed_motions([p["motion"] for p in run.pairs])

    def select(model: Any) -> dict[str, float]:
        rows = generated_rows(model, captions, frames, bones=run.data.bones, seed=seed,
                              desc="validation motions")
        m = guo_metrics(text, ev.embed_motions(rows), real, repeats=repeats, seed=seed,
                        batch_size=batch_size)
        top3 = float(m[TOP3][0])
        return {"select": -top3, **{k: float(m[k][0]) for k in (TOP3, FID, DIVERSITY)}}
    name = evaluator if isinstance(evaluator, (str, Path)) else type(evaluator).__name__
    key = f"top-3 under {name} of {len(run.pairs)} {split} pairs of {data} (seed {seed})"
    select.key = key   # type: ignore[attr-defined]
    return select


def format_scores(val: dict) -> str:
    """``"top-3 0.636, FID 23.8, diversity 8.5"`` of a validation record ('' without
    them)."""
    if TOP3 not in val:
        return ""
    return f"top-3 {val[TOP3]:.3f}, FID {val[FID]:.1f}, diversity {val[DIVERSITY]:.1f}"

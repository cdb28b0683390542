"""The text-to-motion yardstick of the papers (Guo et al. 2022) with any text-motion
evaluator (``models.evaluator``: one trained here, or the public weights).

:func:`guo_metrics` takes embeddings; :func:`score_t2m` embeds captions and motion rows
(the evaluator's input: ``(T, D)`` rows in its own units, e.g. HumanML3D vectors) first.
Each repetition shuffles the test pairs anew (and, when ``generated`` is a function of the
repetition, generates anew, as the papers do); every figure is the mean and 95 % interval of
``repeats`` repetitions (``metrics.t2m.repeat``):

* ``R-precision top-1/2/3``: texts ranking their own motion among 32 (batches of 32, the
  last incomplete one dropped); ``MM-Dist``: mean text-motion distance over those batches;
* ``FID``: generated motion embeddings against the real ones (a separate set, e.g. the
  training motions, or the test motions when scoring generations; never a set against
  itself unless asked);
* ``Diversity``: mean distance of ``diversity_times`` random pairs of generated motions
  (300 as the papers; fewer when there are not more motions than that);
* TMR's retrieval (``metrics.t2m.retrieval_metrics``): among all test pairs and in batches
  of 32, R@1/2/3/5/10 (percent) and median rank, both directions, on the first repetition.

``multimodality_score`` gives MultiModality from several generations per text.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.t2m import (diversity, fid, mm_dist, multimodality,
                                               r_precision, repeat, retrieval_metrics)

Generated = Sequence | Callable[[int], Sequence]


def guo_metrics(text_emb, motion_emb, real_emb, *, repeats: int = 20, seed: int = 0,
                batch_size: int = 32, diversity_times: int = 300
                ) -> dict[str, tuple[float, float]]:
    """Text (N, D) and paired motion (N, D) embeddings, real motion embeddings (M, D) for
    FID -> ``{name: (mean, 95 % half interval)}`` over ``repeats`` shuffles (module
    docstring). ``motion_emb`` may be a function ``i -> (N, D)`` (a new generation for
    repetition i)."""
    text = np.asarray(text_emb, dtype=float)
    real = np.asarray(real_emb, dtype=float)
    if len(text) < batch_size:
        raise MotionlangError(f"the yardstick needs at least {batch_size} pairs, got {len(text)}")
    times = min(diversity_times, len(text) - 1)

    def once(i: int) -> dict[str, float]:
        motion = np.asarray(motion_emb(i) if callable(motion_emb) else motion_emb, dtype=float)
        g = np.random.default_rng([seed, i])
        order = g.permutation(len(text))
        rp = r_precision(text[order], motion[order], 3, batch_size)
        return {"R-precision top-1": rp[0], "R-precision top-2": rp[1],
                "R-precision top-3": rp[2], "FID": fid(real, motion),
                "MM-Dist": mm_dist(text[order], motion[order], batch_size),
                "Diversity": diversity(motion, times, g)}

    return repeat(once, repeats)


def retrieval_table(text_emb, motion_emb, batch_size: int = 32) -> dict[str, float]:
    """TMR's measures among all pairs (``all/...``) and in batches of ``batch_size``
    (``b32/...``)."""
    out = {f"all/{k}": v for k, v in retrieval_metrics(text_emb, motion_emb).items()}
    if len(text_emb) >= batch_size:
        out.update({f"b{batch_size}/{k}": v for k, v in retrieval_metrics(
            text_emb, motion_emb, batch_size=batch_size).items()})
    return out


def score_t2m(evaluator, captions: Sequence[str], generated: Generated, real: Sequence, *,
              tokens: Sequence | None = None, repeats: int = 20, seed: int = 0,
              batch_size: int = 32, diversity_times: int = 300) -> dict:
    """Captions, the motion rows made (or recorded) for them — a list, or ``i -> list``
    for a new generation per repetition — and real motion rows for FID -> ``{"guo":
    {name: (mean, interval)}, "retrieval": {name: value}}``.

    ``tokens``: the captions' ``word/POS`` tokens where the data has them."""
    text = evaluator.embed_texts(list(captions), tokens)
    real_emb = evaluator.embed_motions(list(real))
    first = evaluator.embed_motions(list(generated(0) if callable(generated) else generated))
    if len(first) != len(text):
        raise MotionlangError(f"{len(text)} captions but {len(first)} motions")
    motion = (lambda i: first if i == 0 else evaluator.embed_motions(list(generated(i)))) \
        if callable(generated) else first
    return {"guo": guo_metrics(text, motion, real_emb, repeats=repeats, seed=seed,
                               batch_size=batch_size, diversity_times=diversity_times),
            "retrieval": retrieval_table(text, first, batch_size)}


def multimodality_score(evaluator, samples: Sequence[Sequence], *, times: int = 10,
                        repeats: int = 20, seed: int = 0) -> tuple[float, float]:
    """``samples[i]``: S > ``times`` motions generated for text i -> MultiModality (mean,
    interval) over ``repeats`` draws of the pairs."""
    emb = np.stack([evaluator.embed_motions(list(s)) for s in samples])   # (texts, S, D)
    return repeat(lambda i: multimodality(emb, times, np.random.default_rng([seed, i])), repeats)


def format_table(result: dict) -> str:
    """:func:`score_t2m`'s result as text lines ``name: mean +- interval``."""
    lines = [f"{k}: {m:.4f} +- {h:.4f}" for k, (m, h) in result["guo"].items()]
    lines += [f"{k}: {v:.2f}" for k, v in result.get("retrieval", {}).items()]
    return "\n".join(lines)

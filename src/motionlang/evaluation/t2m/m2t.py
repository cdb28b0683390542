"""The motion-to-text half of the yardstick: descriptions of the test motions scored against
their captions (BLEU@1, BLEU@4, ROUGE-L, CIDEr) and under a text-motion evaluator
(R-precision and MM-Dist of the descriptions, as TM2T, Guo et al. 2022b, reports them).

Rows (:func:`m2t_table`):

* ground truth: each test pair's own caption (``pairs[i]["caption"]``), the ceiling;
* nearest neighbour: the first caption of the training motion nearest in summary statistics
  (mean and standard deviation over time of the evaluator's input rows, each dimension
  scaled by its spread over the training motions) — a description that needs no model and
  no evaluator, so it cannot favour either;
* each model: one description per test motion (e.g. an M2L's best beam hypothesis,
  :func:`describe_motions`).

Text measures compare every row's description with the *other* captions of its motion (the
pair's own caption is the ground-truth row's hypothesis, so it cannot also be a reference);
motions with a single caption are left out of them, and the table's title says how many
counted. R-precision: the description's text embedding ranks the 32 motions of its batch
(``metrics.t2m.r_precision``), ``repeats`` shuffles, mean and 95 % interval.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.datasets.text import normalize
from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.t2m import mm_dist, r_precision, repeat
from motionlang.evaluation.seq2seq import summary, text_scores
from motionlang.models.registry import describer
from motionlang.utils.progress import progress

GROUND_TRUTH, NEAREST = "ground truth", "nearest neighbour"


def other_references(references: Sequence[Sequence[str]], captions: Sequence[str]
                     ) -> list[list[str]]:
    """Per item, its normalised references without (one copy of) its own caption."""
    out = []
    for refs, own in zip(references, captions):
        rest = [normalize(r) for r in refs]
        if normalize(own) in rest:
            rest.remove(normalize(own))
        out.append(rest)
    return out


def nearest_captions(train_items: Sequence[dict], pairs: Sequence[dict]) -> list[str]:
    """The nearest-neighbour row: for each test pair, the first caption of the training motion
    (items ``{"id", "motion": (T, D) rows, "caption"}``) whose summary (mean and std of its
    rows over time, scaled per dimension by the training motions' spread) is nearest."""
    first: dict[str, dict] = {}
    for it in train_items:
        first.setdefault(it["id"], it)
    if not first:
        raise MotionlangError("no training motions for the nearest-neighbour descriptions")
    bank = np.stack([summary(np.asarray(it["motion"], dtype=float)) for it in first.values()])
    scale = bank.std(axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    bank = bank / scale
    captions = [it["caption"] for it in first.values()]
    out = []
    for p in pairs:
        d = ((bank - summary(np.asarray(p["motion"], dtype=float)) / scale) ** 2).sum(1)
        out.append(captions[int(d.argmin())])
    return out


def describe_motions(model, motions: Sequence, *, width: int = 5, desc: str = "describe"
                     ) -> list[str]:
    """An M2L's likeliest beam hypothesis (``models.seq2seq.decode.search.describe``, beam ``width``,
    the paper's order; ``describe`` shows its minimum-Bayes-risk choice first) for each
    ``Motion``."""
    describe = describer(model)
    return [describe(model, m, width=width, length_penalty=0.0, rank="logp")[0][0]
            for m in progress(list(motions), desc=desc, unit="motions")]


def text_measures(references: Sequence[Sequence[str]], hypotheses: Sequence[str]
                  ) -> dict[str, float]:
    """BLEU@1, BLEU@4, ROUGE-L and CIDEr (``evaluation.seq2seq.text_scores``) of one
    hypothesis per item (normalised first) against its references; items without references
    are skipped."""
    keep = [i for i, r in enumerate(references) if r]
    if not keep:
        return {}
    got = text_scores([list(references[i]) for i in keep],
                      [normalize(hypotheses[i]) for i in keep])
    names = {"bleu1": "BLEU@1", "bleu": "BLEU@4", "rouge_l": "ROUGE-L", "cider": "CIDEr"}
    return {names[k]: got[k] for k in names if k in got}


def description_precision(evaluator, descriptions: Sequence[str], motion_emb, *,
                          repeats: int = 20, seed: int = 0, batch_size: int = 32
                          ) -> dict[str, tuple[float, float]]:
    """R-precision top-1/2/3 and MM-Dist of descriptions (one per motion) against the
    motions' embeddings (N, D), over ``repeats`` shuffles -> ``{name: (mean, interval)}``."""
    text = evaluator.embed_texts(list(descriptions))
    motion = np.asarray(motion_emb, dtype=float)

    def once(i: int) -> dict[str, float]:
        order = np.random.default_rng([seed, i]).permutation(len(text))
        rp = r_precision(text[order], motion[order], 3, batch_size)
        return {"R-precision top-1": rp[0], "R-precision top-2": rp[1],
                "R-precision top-3": rp[2],
                "MM-Dist": mm_dist(text[order], motion[order], batch_size)}
    return repeat(once, repeats)


def m2t_table(evaluator, pairs: Sequence[dict], references: Sequence[Sequence[str]],
              train_items: Sequence[dict], described: dict[str, Sequence[str]] | None = None,
              *, repeats: int = 20, seed: int = 0, batch_size: int = 32
              ) -> tuple[dict[str, dict], int]:
    """Test ``pairs`` (``{"id", "motion", "caption"}``, one per motion), every caption of each
    pair's motion, training items (nearest neighbour) and ``described`` (row name -> one
    description per pair) -> (``{row: {measure: value or (mean, interval)}}``, how many
    motions the text measures counted: those with a second caption)."""
    if len(pairs) < batch_size:
        raise MotionlangError(f"the yardstick needs at least {batch_size} pairs, got "
                              f"{len(pairs)}")
    if len(references) != len(pairs):
        raise MotionlangError(f"{len(references)} reference lists for {len(pairs)} pairs")
    own = {p.get("id") for p in pairs}
    captions = [p["caption"] for p in pairs]
    rows = {GROUND_TRUTH: captions,
            NEAREST: nearest_captions([it for it in train_items if it["id"] not in own],
                                      pairs),
            **(described or {})}
    refs = other_references(references, captions)
    motion_emb = evaluator.embed_motions([p["motion"] for p in pairs])
    table = {}
    for name, texts in rows.items():
        if len(texts) != len(pairs):
            raise MotionlangError(f"{name}: {len(texts)} descriptions for {len(pairs)} motions")
        table[name] = {**text_measures(refs, texts),
                       **description_precision(evaluator, texts, motion_emb, repeats=repeats,
                                               seed=seed, batch_size=batch_size)}
    return table, sum(1 for r in refs if r)

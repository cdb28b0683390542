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
:func:`guo_table` makes the rows of ``motionlang evaluate-t2m --protocol guo`` (ground truth,
nearest neighbour, standing still, each model's :func:`generated_rows`) and
:func:`markdown_table` prints them.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from motionlang.datasets.evaluator_items import joints_rows
from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.t2m import (
    diversity,
    fid,
    mm_dist,
    multimodality,
    r_precision,
    repeat,
    retrieval_metrics,
)
from motionlang.evaluation.retrieval import SentenceIndex
from motionlang.features.h3d_vectors import H3D_BODIES, joints_to_vectors, vectors_to_joints
from motionlang.models.t2m import text_to_motion
from motionlang.utils.progress import progress

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


# -- the table of ``motionlang evaluate-t2m --protocol guo`` --------------------------------
#: the retrieval measures the table shows (text -> motion, among all test pairs): name in
#: ``metrics.t2m.retrieval_metrics`` -> column
TABLE_RETRIEVAL = {"t2m/R01": "TMR R@1 %", "t2m/R05": "TMR R@5 %", "t2m/R10": "TMR R@10 %",
                   "t2m/MedR": "TMR MedR"}
GROUND_TRUTH, NEAREST, STILL = "ground truth", "nearest neighbour", "standing still"


def evaluator_body(evaluator) -> str:
    """The HumanML3D body (``"kit"``: 251 values a row, ``"smpl"``: 263) an evaluator reads."""
    for name, spec in H3D_BODIES.items():
        if spec.dim == evaluator.config.motion_dim:
            return name
    raise MotionlangError(f"an evaluator of {evaluator.config.motion_dim} values a frame reads "
                          "no HumanML3D body (251: kit, 263: smpl)")


def positions_rows(p21: np.ndarray, bones=None) -> np.ndarray:
    """Global 21-joint positions (T >= 2, 21, 3) metres at 12.5 Hz (what every text-to-motion
    model gives, ``models.t2m``) -> (T-1, 251) float32 rows of the ``kit`` body (mm), laid
    on ``bones`` (20 lengths, m: an evaluator's ``config.bones``) if given."""
    p = np.asarray(p21, dtype=float)
    if len(p) < 2:
        p = np.repeat(p[:1], 2, axis=0)
    return joints_rows(p, "kit", bones)


def still_rows(rows: np.ndarray, body: str) -> np.ndarray:
    """The rows of a motion's first pose held for as many frames (``body``'s layout)."""
    spec = H3D_BODIES[body]
    pose = vectors_to_joints(np.asarray(rows)[:1], spec)[0]
    return joints_to_vectors(np.repeat(pose[None], len(rows) + 1, axis=0),
                             spec)[0].astype(np.float32)


def test_pairs(items: Sequence[dict], seed: int = 0) -> list[dict]:
    """One item per motion (items: ``datasets.evaluator_items`` items, several captions per
    motion id), its caption drawn with ``seed``, in the items' order of motions."""
    by_id: dict[str, list[dict]] = {}
    for it in items:
        by_id.setdefault(it["id"], []).append(it)
    rng = np.random.default_rng(seed)
    return [group[rng.integers(len(group))] for group in by_id.values()]


def r_precision_miss(items: Sequence[dict], *, seed: int = 0, batch_size: int = 32,
                     top: int = 3) -> Callable | None:
    """A validation score for training an evaluator (``training.trainer.Trainer``'s
    ``select``): evaluator -> 1 - R-precision top-``top`` of one caption per motion of
    ``items`` (:func:`test_pairs`), one seeded shuffle in batches of ``batch_size``; None
    when there are fewer motions than a batch."""
    pairs = test_pairs(items, seed)
    if len(pairs) < batch_size:
        return None
    captions = [p["caption"] for p in pairs]
    tokens = [p.get("tokens") for p in pairs]
    motions = [p["motion"] for p in pairs]

    def miss(evaluator) -> float:
        rp = r_precision(evaluator.embed_texts(captions, tokens),
                         evaluator.embed_motions(motions), top, batch_size, rng=seed)
        return 1.0 - float(rp[top - 1])
    return miss


def nearest_rows(train_items: Sequence[dict], captions: Sequence[str]) -> list[np.ndarray]:
    """The nearest-neighbour baseline: for each caption the training motion whose caption
    is nearest in bag of words (``evaluation.retrieval.SentenceIndex``)."""
    motion = {it["id"]: it["motion"] for it in train_items}
    index = SentenceIndex((it["id"], it["caption"]) for it in train_items)
    return [motion[index.nearest(c)[0]] for c in captions]


def guo_table(evaluator, pairs: Sequence[dict], train_items: Sequence[dict],
              generated: dict[str, Sequence] | None = None, *,
              samples: dict[str, Sequence[Sequence]] | None = None,
              reference_items: Sequence[dict] | None = None, repeats: int = 20,
              seed: int = 0, batch_size: int = 32, diversity_times: int = 300,
              mm_times: int = 10) -> dict[str, dict]:
    """The yardstick's rows for test ``pairs`` (items ``{"motion", "caption", "tokens"}``,
    one per test motion, :func:`test_pairs`) -> ``{row: {measure: (mean, interval) or
    value}}``.

    Rows: the ground truth (its FID between the test and the ``train_items`` motions, or
    the ``reference_items``' when given, e.g. the validation split: real against real),
    the nearest-neighbour baseline (:func:`nearest_rows`; training motions that are also
    test pairs are left out of both, so that a split evaluated against itself never finds
    its own motions), standing still in the first pose (:func:`still_rows`), then
    ``generated`` (name -> motion rows for the pairs, in the evaluator's layout; or a
    function ``i -> rows``, a new generation for each repetition i, the first also giving
    the retrieval measures). Every row's FID but the ground truth's is against
    the test motions. ``samples`` (name -> per pair, S motions generated for its caption)
    adds MultiModality (``mm_times`` pairs of the S) to that row. Each row also has TMR's
    :data:`TABLE_RETRIEVAL` measures (first shuffle, all pairs).
    """
    if not pairs:
        raise MotionlangError("no test pairs to evaluate")
    body = evaluator_body(evaluator)
    own = {p.get("id") for p in pairs}
    train_items = [it for it in train_items if it["id"] not in own]
    if not train_items:
        raise MotionlangError("no training motions apart from the evaluated ones (the "
                              "nearest-neighbour baseline and the ground truth's FID need them)")
    captions = [p["caption"] for p in pairs]
    tokens = [p.get("tokens") for p in pairs]
    truth = [p["motion"] for p in pairs]
    rows = {GROUND_TRUTH: truth, NEAREST: nearest_rows(train_items, captions),
            STILL: [still_rows(m, body) for m in truth], **(generated or {})}
    text = evaluator.embed_texts(captions, tokens)
    test_emb = evaluator.embed_motions(truth)
    seen, train_motions = set(), []
    reference = train_items if reference_items is None else \
        [it for it in reference_items if it["id"] not in own]
    for it in reference:
        if it["id"] not in seen:
            seen.add(it["id"])
            train_motions.append(it["motion"])
    table = {}
    for name, motions in rows.items():
        first = motions(0) if callable(motions) else motions
        if len(first) != len(pairs):
            raise MotionlangError(f"{name}: {len(first)} motions for {len(pairs)} captions")
        emb = test_emb if name == GROUND_TRUTH else evaluator.embed_motions(list(first))
        # a function of the repetition: a new generation for each (as the papers measure)
        per_repeat = (lambda i, m=motions, e=emb: e if i == 0 else
                      evaluator.embed_motions(list(m(i)))) if callable(motions) else emb
        row = guo_metrics(text, per_repeat, test_emb, repeats=repeats, seed=seed,
                          batch_size=batch_size, diversity_times=diversity_times)
        if name == GROUND_TRUTH:   # real against real: never a set against itself
            row["FID"] = ((fid(test_emb, evaluator.embed_motions(train_motions)), 0.0)
                          if len(train_motions) > 1 else (float("nan"), 0.0))
        if samples and name in samples:
            row["MultiModality"] = multimodality_score(evaluator, samples[name],
                                                       times=mm_times, repeats=repeats,
                                                       seed=seed)
        got = retrieval_metrics(text, emb)
        row.update({col: got[k] for k, col in TABLE_RETRIEVAL.items()})
        table[name] = row
    return table


def markdown_table(table: dict[str, dict], title: str = "") -> str:
    """:func:`guo_table`'s rows as a Markdown table: ``mean ± interval`` (3 decimals) for
    the repeated measures, one value for the others (retrieval: 1 decimal; text scores such
    as BLEU: 3); "–" where a row has none."""
    columns = list(dict.fromkeys(k for row in table.values() for k in row))
    lines = [f"{title}\n" if title else "",
             "| | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]

    def cell(v, column: str) -> str:
        if v is None:
            return "–"
        if isinstance(v, (tuple, list)):
            return f"{v[0]:.3f} ± {v[1]:.3f}"
        if isinstance(v, float):   # retrieval: percentages and ranks; text scores: 0-1 (10)
            return f"{v:.1f}" if column in TABLE_RETRIEVAL.values() else f"{v:.3f}"
        return str(v)
    for name, row in table.items():
        lines.append(f"| {name} | " + " | ".join(cell(row.get(c), c) for c in columns) + " |")
    return "\n".join(x for x in lines if x) + "\n"


def generated_rows(model, captions: Sequence[str], n_frames: Sequence[int], *,
                   desc: str = "generate", bones=None, **kw) -> list[np.ndarray]:
    """A text-to-motion model's motions for ``captions``, each ``n_frames[i]`` frames at
    12.5 Hz (``models.t2m.TextToMotion.positions21``; ``kw`` go to it, e.g. ``method``,
    ``seed``), as ``kit`` rows (:func:`positions_rows`, on ``bones`` if given)."""
    t2m = text_to_motion(model)
    if t2m.deterministic:   # no sampling options
        kw = {k: v for k, v in kw.items() if k not in ("method", "seed")}
    return [positions_rows(t2m.positions21(c, max(2, int(n)), **kw), bones)
            for c, n in progress(list(zip(captions, n_frames)), desc=desc, unit="motions")]

"""Evaluation of the seq2seq models (Plappert, Mandery & Asfour 2018, Section 5).

- M2L: corpus BLEU (1-4-grams, all references of a motion) of the 1st..W-th beam
  hypotheses (the paper's Table 2), BLEU-1, ROUGE-L, CIDEr and the rank/BLEU correlation.
- Nearest-neighbour baseline: a test motion gets the first description of the closest
  training motion (Euclidean distance between per-dimension mean and std over time of the
  model frames, a length-independent summary).
- L2M round trip (Tables 3-4): generate a motion from every reference sentence of a test
  motion, describe it with the M2L model, BLEU of those descriptions against the motion's
  references; relative performance = that BLEU / the M2L BLEU on the real motions.
  Its baseline: the motion of the training sentence closest in bag of words
  (``evaluation.retrieval``), described the same way.

Inputs are model frames (``{id: (T, F) array}``, as in ``PairData.sequences`` offset 0) and
references ``{id: [sentences]}``; hypotheses and references are both compared after
``datasets.text.normalize``.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from motionlang.datasets.bandai_text import names_content, names_style
from motionlang.datasets.synth import extract, score
from motionlang.datasets.text import normalize
from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics import text as tm
from motionlang.models.seq2seq.decode.rerank import check_same_features, rerank
from motionlang.models.seq2seq.decode.search import describe_features, generate_features
from motionlang.utils.progress import progress


def _refs(references: Mapping[str, Sequence[str]], ids: Sequence[str]) -> list[list[str]]:
    return [[normalize(s) for s in references[i]] for i in ids]


def text_scores(refs: list[list[str]], hyps: list[str]) -> dict[str, float]:
    """BLEU, BLEU-1, ROUGE-L and (if pycocoevalcap is installed) CIDEr of one hypothesis
    per item."""
    out = {"bleu": tm.corpus_bleu(refs, hyps), "bleu1": tm.bleu1(refs, hyps),
           "rouge_l": tm.rouge_l(refs, hyps)}
    try:
        out["cider"] = tm.cider(refs, hyps)
    except Exception:  # optional dependency missing: report the others
        pass
    return out


def evaluate_m2l(model, frames: Mapping[str, np.ndarray], references: Mapping[str, Sequence[str]],
                 width: int = 5, length_penalty: float = 0.0, *, rank: str = "logp") -> dict:
    """Describe every motion with beam width W (its sentences ordered by ``rank``,
    ``models.seq2seq.decode.search.describe_features``) and score the hypotheses.

    Returns ``{"n", "width", "bleu_by_rank" [W], "rank_bleu_spearman", "bleu", "bleu1",
    "rouge_l", ("cider"), "examples"}`` (scores of the top hypothesis).
    """
    ids = sorted(frames)
    ranked = []
    for i in progress(ids, desc="describe", unit="motion"):
        hyps = [normalize(t) for t, _ in describe_features(model, frames[i], width=width,
                                                           length_penalty=length_penalty,
                                                           rank=rank)]
        ranked.append((hyps + [hyps[-1]] * width)[:width])  # pad rare short beams
    refs = _refs(references, ids)
    top = [r[0] for r in ranked]
    return {"n": len(ids), "width": width, "bleu_by_rank": tm.bleu_by_rank(refs, ranked),
            "rank_bleu_spearman": tm.rank_bleu_correlation(refs, ranked),
            **text_scores(refs, top),
            "examples": [{"id": i, "hypotheses": r, "references": f}
                         for i, r, f in list(zip(ids, ranked, refs))[:5]],
            "all": [{"id": i, "hypotheses": r} for i, r in zip(ids, ranked)]}


def summary(x: np.ndarray) -> np.ndarray:
    """(T, F) frames -> (2F,) mean and std over time."""
    return np.concatenate([x.mean(0), x.std(0)])


def nearest_neighbour_descriptions(train_frames: Mapping[str, np.ndarray],
                                   train_refs: Mapping[str, Sequence[str]],
                                   query_frames: Mapping[str, np.ndarray]) -> dict[str, str]:
    """{query id: first description of the nearest described training motion}."""
    tids = [i for i in sorted(train_frames) if train_refs.get(i)]
    bank = np.stack([summary(train_frames[i]) for i in tids])
    out = {}
    for q, x in query_frames.items():
        d = ((bank - summary(x)) ** 2).sum(1)
        out[q] = normalize(train_refs[tids[int(d.argmin())]][0])
    return out


def evaluate_nn_baseline(train_frames, train_refs, frames, references) -> dict:
    ids = sorted(frames)
    nn = nearest_neighbour_descriptions(train_frames, train_refs, {i: frames[i] for i in ids})
    return {"n": len(ids), **text_scores(_refs(references, ids), [nn[i] for i in ids])}


def evaluate_round_trip(l2m, m2l, references: Mapping[str, Sequence[str]],
                        m2l_bleu: float, *, method: str = "mean", width: int = 1,
                        max_frames: int | None = None, seed: int = 0,
                        temperature: float = 1.0, reranker=None,
                        length_norm: bool = False) -> dict:
    """Generate from each reference sentence (``models.seq2seq.decode.search.generate_features`` with
    ``method``, ``width``, ``temperature``, ``length_norm``; its best hypothesis), describe
    the result, score against the motion's references. Both models must share one feature
    set (same frames). :func:`round_trip_of` runs it with a text-to-motion model's options.

    reranker: another M2L model; the described hypothesis is then the one of the ``width``
    under which it finds the sentence likeliest (``models.seq2seq.decode.rerank``), not the L2M's likeliest.
    It must not be ``m2l`` itself, which would grade its own choice.

    Returns ``{"n_sentences", "bleu", "bleu1", "rouge_l", ("cider"), "relative",
    "descriptions"}`` with relative = bleu / m2l_bleu (NaN if m2l_bleu is below
    ``MIN_BLEU``, when the ratio means nothing) and
    descriptions = [[motion id, sentence, description of the generated motion], ...].
    """
    if reranker is not None:
        if reranker is m2l:
            raise MotionlangError("the round trip's reranker must not be its describer")
        check_same_features(l2m, reranker)

    def motion(sentence):
        hyps = generate_features(l2m, sentence, width=width, method=method,
                                 max_frames=max_frames, seed=seed, temperature=temperature,
                                 length_norm=length_norm)
        if reranker is not None:
            hyps = rerank(hyps, reranker, sentence)
        return hyps[0][0]
    return round_trip(motion, m2l, references, m2l_bleu)


def round_trip_model(t2m, what: str = "the round trip's model") -> None:
    """Raise :class:`MotionlangError` (naming ``what``) unless the text-to-motion model
    ``t2m`` (``models.t2m.TextToMotion``) can make the round trip's motions: ranked
    hypotheses of frames in its own features, which the M2L describes (an L2M)."""
    if "hypotheses" not in t2m.capabilities:
        kind = getattr(t2m.model, "kind", type(t2m.model).__name__)
        raise MotionlangError(f"{what}: the round trip describes ranked motions in the "
                              f"model's own features; a {kind} model gives one motion in "
                              "positions (an L2M gives them)")


def round_trip_of(t2m, m2l, references: Mapping[str, Sequence[str]], m2l_bleu: float, *,
                  max_frames: int | None = None, seed: int = 0) -> dict:
    """:func:`evaluate_round_trip` of a text-to-motion model (``models.t2m``, checked by
    :func:`round_trip_model`) decoding with its own options: ``method`` (unset: "mean"),
    ``width``, ``temperature``, ``length_norm`` and the reranker its ``rerank`` names."""
    round_trip_model(t2m)
    o = t2m.options
    method = o.method or "mean"
    return evaluate_round_trip(t2m.model, m2l, references, m2l_bleu, method=method,
                               width=o.width if method != "mean" else 1,
                               temperature=o.temperature, length_norm=o.length_norm,
                               reranker=t2m.reranker, max_frames=max_frames, seed=seed)


def evaluate_round_trip_nn(index, train_frames: Mapping[str, np.ndarray], m2l,
                           references: Mapping[str, Sequence[str]], m2l_bleu: float) -> dict:
    """The round trip's nearest-neighbour baseline: each sentence gets the motion (model
    frames from ``train_frames``) of the closest training sentence in bag of words
    (``retrieval.SentenceIndex`` whose keys are motion ids); same result as
    :func:`evaluate_round_trip`."""
    return round_trip(lambda s: train_frames[index.nearest(s)[0]], m2l, references, m2l_bleu)


# BLEU below this (0.1 of 100 points) means no n-gram of some order matched: a smoothed value
# such as 1e-154 whose ratios (2.4e155, or 0.945 for two of them) say nothing
MIN_BLEU = 1e-3


def relative_bleu(bleu: float, m2l_bleu: float) -> float:
    """The round trip's BLEU as a fraction of M2L's on the real motions; NaN (undefined)
    when M2L's is below :data:`MIN_BLEU`, and 0 for a round trip's below it."""
    if not m2l_bleu >= MIN_BLEU:
        return float("nan")
    return bleu / m2l_bleu if bleu >= MIN_BLEU else 0.0


def round_trip(motion_for, m2l, references: Mapping[str, Sequence[str]],
               m2l_bleu: float) -> dict:
    """Describe ``motion_for(sentence) -> (T, F) frames`` of every reference sentence with
    ``m2l`` (top hypothesis of width 1) and score as :func:`evaluate_round_trip` says."""
    refs, hyps = [], []
    pairs = [(i, s) for i in sorted(references) for s in references[i]]
    for i, sentence in progress(pairs, desc="round trip", unit="sentence"):
        hyps.append(normalize(describe_features(m2l, motion_for(sentence), width=1)[0][0]))
        refs.append([normalize(s) for s in references[i]])
    scores = text_scores(refs, hyps)
    rel = relative_bleu(scores["bleu"], m2l_bleu)
    return {"n_sentences": len(pairs), **scores, "relative": rel,
            "descriptions": [[i, s, h] for (i, s), h in zip(pairs, hyps)]}


def round_trip_parameter_accuracy(descriptions: Sequence[Sequence[str]],
                                  truths: Mapping[str, Sequence]) -> dict:
    """:func:`parameter_accuracy` of the round trip's descriptions (one per sentence);
    the truth of each is its motion's, which the sentence describes."""
    texts = {f"{i}#{k}": d for k, (i, _, d) in enumerate(descriptions)}
    return parameter_accuracy(texts, {key: truths[key.split("#")[0]] for key in texts})


def actions_named(descriptions: Sequence[Sequence[str]], truths: Mapping[str, Sequence]
                  ) -> dict:
    """Procedural corpus: how often the round trip's descriptions name each true action, by
    its place in its motion. Shows whether generated motions lose their later actions.

    descriptions: ``(id, sentence, description)`` triples; truths: id -> ground-truth
    primitives. A true primitive counts as named when the description names its action at
    least once (``datasets.synth.extract``).
    Returns {place: fraction named, "n_" + place: primitives} for place "first" and "later"
    (motions of several primitives) and "only" (motions of one).
    """

    named = {"first": 0, "later": 0, "only": 0}
    total = dict.fromkeys(named, 0)
    for i, _, text in descriptions:
        said = {p.action for p in extract(text)}
        truth = list(truths[i])
        for k, prim in enumerate(truth):
            place = "only" if len(truth) == 1 else ("first" if k == 0 else "later")
            total[place] += 1
            named[place] += prim.action in said
    out: dict = {}
    for place in named:
        out[place] = named[place] / total[place] if total[place] else float("nan")
        out["n_" + place] = total[place]
    return out


def markdown_table(results: Mapping[str, Mapping[str, float]]) -> str:
    """{row name: {metric: value}} -> a markdown table over the metrics they share."""
    cols = ["bleu", "bleu1", "rouge_l", "cider", "relative"]
    cols = [c for c in cols if any(c in r for r in results.values())]
    lines = ["| | " + " | ".join(cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for name, r in results.items():
        cells = [f"{r[c]:.3f}" if c in r and r[c] == r[c] else "" for c in cols]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def parameter_accuracy(texts: Mapping[str, str], truths: Mapping[str, Sequence]) -> dict:
    """Procedural corpus: are the parameters a description states right?

    texts: id -> one description (e.g. the top M2L hypothesis); truths: id -> the sample's
    ground-truth primitives (``motionlang.datasets.synth.ground_truth(meta)``).
    Returns {"n", "actions_match" (fraction of descriptions naming exactly the true action
    sequence), field: accuracy over the descriptions that state it (NaN if none),
    field + "_stated": how many stated it} for side, count, direction, speed.
    """

    fields = ("side", "count", "direction", "speed")
    right = {f: 0 for f in fields}
    stated = {f: 0 for f in fields}
    match = 0
    for i, text in texts.items():
        s = score(text, list(truths[i]))
        match += bool(s["actions_match"])
        for f in fields:
            right[f] += s[f][0]
            stated[f] += s[f][1]
    out: dict = {"n": len(texts), "actions_match": match / max(1, len(texts))}
    for f in fields:
        out[f] = right[f] / stated[f] if stated[f] else float("nan")
        out[f + "_stated"] = stated[f]
    return out


def named_line(named: dict) -> str:
    """``evaluation.seq2seq.actions_named``'s result as one line of text."""
    return ", ".join(f"{place} {named[place]:.1%} of {named['n_' + place]}"
                     for place in ("first", "later", "only"))


def label_accuracy(texts: Mapping[str, str], labels: Mapping[str, Mapping[str, str]]) -> dict:
    """Labelled takes (Bandai): does a description name the take's action and its style?

    texts: id -> one description; labels: id -> ``{"content", "style"}``. Content by
    ``bandai_text.names_content``, style by ``bandai_text.names_style`` (the grammar's
    synonyms; "normal" also when no style is named). Returns ``{"n", "content", "style",
    "both"}`` (fractions) and ``"by_content"`` / ``"by_style"``: ``{label: [right, of]}``.
    """
    right = {"content": 0, "style": 0, "both": 0}
    by: dict[str, dict[str, list[int]]] = {"by_content": {}, "by_style": {}}
    for i, text in texts.items():
        c, s = labels[i]["content"], labels[i]["style"]
        ok_c, ok_s = names_content(text, c), names_style(text, s)
        right["content"] += ok_c
        right["style"] += ok_s
        right["both"] += ok_c and ok_s
        for key, lab, ok in (("by_content", c, ok_c), ("by_style", s, ok_s)):
            cell = by[key].setdefault(lab, [0, 0])
            cell[0] += ok
            cell[1] += 1
    n = len(texts)
    return {"n": n, **{k: v / n if n else float("nan") for k, v in right.items()},
            **{k: dict(sorted(v.items())) for k, v in by.items()}}

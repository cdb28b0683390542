"""Text metrics for motion descriptions, as pure functions.

Conventions: ``references[i]`` is the list of ALL reference sentences of item i and
``hypotheses[i]`` the one hypothesis for it; a sentence is a string (split on whitespace,
so pass normalised text) or a list of tokens. Scores are in [0, 1] (CIDEr: [0, 10]).

Libraries (maintained ones, named here): BLEU from ``nltk.translate.bleu_score``
(corpus-level: n-gram counts and lengths are summed over the corpus before the geometric
mean, as in Papineni et al. 2002 and Plappert et al. 2018); ROUGE-L from Google's
``rouge_score``; CIDEr(-D) from ``pycocoevalcap`` (optional).
"""
from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np

from motionlang.errors import MotionlangError

Sentence = str | Sequence[str]


def _toks(s: Sentence) -> list[str]:
    return s.split() if isinstance(s, str) else list(s)


def _check(references: Sequence[Sequence[Sentence]], hypotheses: Sequence[Sentence]):
    if len(references) != len(hypotheses):
        raise MotionlangError(f"{len(hypotheses)} hypotheses but {len(references)} "
                              "reference lists")
    if any(len(r) == 0 for r in references):
        raise MotionlangError("every item needs at least one reference sentence")
    refs = [[_toks(r) for r in rs] for rs in references]
    return refs, [_toks(h) for h in hypotheses]


def corpus_bleu(references: Sequence[Sequence[Sentence]], hypotheses: Sequence[Sentence],
                max_n: int = 4) -> float:
    """Corpus BLEU with uniform weights over 1..max_n-grams and all references per item.

    No smoothing (the standard corpus score); 0 when some n-gram order has no match.
    """
    from nltk.translate.bleu_score import corpus_bleu as nltk_corpus_bleu

    refs, hyps = _check(references, hypotheses)
    if not hyps:
        return 0.0
    weights = tuple([1.0 / max_n] * max_n)
    with warnings.catch_warnings():  # nltk warns when the score is 0; 0 is the answer here
        warnings.simplefilter("ignore", UserWarning)
        return float(nltk_corpus_bleu(refs, hyps, weights=weights))


def bleu1(references: Sequence[Sequence[Sentence]], hypotheses: Sequence[Sentence]) -> float:
    """Corpus BLEU-1: clipped unigram precision times the brevity penalty."""
    return corpus_bleu(references, hypotheses, max_n=1)


def sentence_bleu(references: Sequence[Sentence], hypothesis: Sentence, max_n: int = 4) -> float:
    """BLEU of one hypothesis, smoothed (Chen & Cherry 2014 method 1) so that short
    sentences without a 4-gram match still get a graded score."""
    from nltk.translate.bleu_score import SmoothingFunction
    from nltk.translate.bleu_score import sentence_bleu as nltk_sentence_bleu

    (refs,), (hyp,) = _check([references], [hypothesis])
    return float(nltk_sentence_bleu(refs, hyp, weights=tuple([1.0 / max_n] * max_n),
                                    smoothing_function=SmoothingFunction().method1))


def rouge_l(references: Sequence[Sequence[Sentence]], hypotheses: Sequence[Sentence]) -> float:
    """Mean over items of the ROUGE-L F-measure against the best-matching reference."""
    from rouge_score.rouge_scorer import RougeScorer

    refs, hyps = _check(references, hypotheses)
    scorer = RougeScorer(["rougeL"])
    scores = [scorer.score_multi([" ".join(r) for r in rs], " ".join(h))["rougeL"].fmeasure
              for rs, h in zip(refs, hyps)]
    return float(np.mean(scores)) if scores else 0.0


def cider(references: Sequence[Sequence[Sentence]], hypotheses: Sequence[Sentence]) -> float:
    """Corpus CIDEr (Vedantam et al. 2015) via pycocoevalcap; document frequencies come
    from these references, so the score is only comparable within one test set."""
    try:
        from pycocoevalcap.cider.cider import Cider
    except ImportError as exc:
        raise MotionlangError("CIDEr needs the 'pycocoevalcap' package "
                              "(pip install pycocoevalcap)") from exc
    refs, hyps = _check(references, hypotheses)
    gts = {i: [" ".join(r) for r in rs] for i, rs in enumerate(refs)}
    res = {i: [" ".join(h)] for i, h in enumerate(hyps)}
    score, _ = Cider().compute_score(gts, res)
    return float(score)


def bleu_by_rank(references: Sequence[Sequence[Sentence]],
                 ranked: Sequence[Sequence[Sentence]], max_n: int = 4) -> list[float]:
    """Corpus BLEU of the r-th hypothesis of every item, r = 1..W (paper's Table 2).

    ``ranked[i]`` holds item i's hypotheses best first; all items need W of them.
    """
    widths = {len(h) for h in ranked}
    if len(widths) != 1:
        raise MotionlangError(f"every item needs the same number of hypotheses, got {widths}")
    W = widths.pop()
    return [corpus_bleu(references, [h[r] for h in ranked], max_n) for r in range(W)]


def rank_bleu_correlation(references: Sequence[Sequence[Sentence]],
                          ranked: Sequence[Sequence[Sentence]]) -> float:
    """Spearman correlation between a hypothesis's rank (1 = most probable) and its
    sentence BLEU, over all (item, rank) pairs. Negative = better-ranked hypotheses
    score higher, which is what a well-calibrated model shows; NaN if BLEU is constant."""
    from scipy.stats import spearmanr

    ranks, scores = [], []
    for refs, hyps in zip(references, ranked):
        for r, h in enumerate(hyps, start=1):
            ranks.append(r)
            scores.append(sentence_bleu(refs, h))
    if len(set(scores)) < 2 or len(set(ranks)) < 2:
        return float("nan")
    return float(spearmanr(ranks, scores).statistic)

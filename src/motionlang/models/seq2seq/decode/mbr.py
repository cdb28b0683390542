"""Minimum Bayes risk ordering of a beam's descriptions (Kumar & Byrne 2004), beyond the paper.

The paper shows the beam's likeliest sentence. When a motion has several right phrasings
("an energetic person raises both hands", "someone raises both arms energetically"), the
likeliest is often the shortest, and the one that shares least with the others. Here each
hypothesis h is ranked by its mean similarity to the beam's sentences,
``sum_h' BLEU+1(h, h') / W`` over all W sentences (h itself included), with BLEU+1 the sentence
BLEU of Lin & Och 2004 (add one to the matches and counts of 2- to 4-grams; unigrams
unsmoothed, so sentences sharing no word score 0): the first is the beam's medoid, the
phrasing it agrees on most. This is minimum Bayes risk decoding with the beam as a uniform
sample of the model's sentences. Weighting the sentences by their renormalised beam
probabilities instead (the textbook evidence distribution) returns the likeliest sentence
almost always, since the beam's probabilities are peaked, and scores below the uniform
weighting on real validation takes (figures in `docs/results/real-motion.md`).
"""
from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence

#: orders of n-grams in BLEU+1
ORDERS = 4


def _ngrams(words: Sequence[str], n: int) -> Counter:
    return Counter(tuple(words[i:i + n]) for i in range(len(words) - n + 1))


def bleu_plus_one(hypothesis: str, reference: str) -> float:
    """Sentence BLEU+1 on whitespace words: n-gram precisions 1..4 (add one to matches and
    counts from 2-grams on), geometric mean, brevity penalty; 1.0 for identical sentences,
    0.0 when no word is shared.

    Example: "a b c" against "a b d": precisions 2/3, (1+1)/(2+1), (0+1)/(1+1), (0+1)/(0+1),
    no penalty: (0.667 * 0.667 * 0.5 * 1) ** 0.25 = 0.687.
    """
    h, r = hypothesis.split(), reference.split()
    matches = [sum((_ngrams(h, n) & _ngrams(r, n)).values()) for n in range(1, ORDERS + 1)]
    if not h or not matches[0]:
        return 0.0
    log_p = math.log(matches[0] / len(h)) + sum(
        math.log((m + 1) / (max(len(h) - n + 1, 0) + 1))
        for n, m in enumerate(matches[1:], start=2))
    brevity = min(1.0, math.exp(1.0 - len(r) / len(h)))
    return brevity * math.exp(log_p / ORDERS)


def mbr_rank(hypotheses: Sequence[tuple[str, float]]) -> list[tuple[str, float]]:
    """``[(sentence, total log P), ...]`` -> the same pairs, highest mean BLEU+1 against the
    whole beam first (ties keep the beam's order, so of two sentences of one length the
    likelier stays first). One or no hypothesis comes back as given."""
    hyps = list(hypotheses)
    if len(hyps) < 2:
        return hyps
    gain = [sum(bleu_plus_one(h, o) for o, _ in hyps) for h, _ in hyps]
    order = sorted(range(len(hyps)), key=lambda i: (-gain[i], i))
    return [hyps[i] for i in order]

"""Minimum Bayes risk ranking of a beam's descriptions (Kumar & Byrne 2004), beyond the paper.

The paper shows the beam's likeliest sentence. When a motion has several right phrasings
("an energetic person raises both hands", "someone raises both arms energetically"), the
likeliest is often the shortest, and the one that shares least with the others. MBR ranks
each hypothesis h by its expected similarity to the beam's sentences under the model's
belief, ``sum_h' P(h') * BLEU+1(h, h')`` with P the beam's probabilities renormalised over the
beam and BLEU+1 the sentence BLEU of Lin & Och 2004 (add one to the matches and counts of
2- to 4-grams; unigrams unsmoothed, so sentences sharing no word score 0); the first is the
description the beam agrees on most. On the packaged M2L's Bandai validation takes (200,
width 5) it raised corpus BLEU-4 from 0.396 to 0.494 (`docs/results/real-motion.md`).
"""
from __future__ import annotations

import math
from collections import Counter
from typing import Sequence

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
    """``[(sentence, total log P), ...]`` -> the same pairs, highest expected BLEU+1 against
    the others first (a hypothesis is not compared with itself; ties keep the beam's order).
    One or no hypothesis comes back as given."""
    hyps = list(hypotheses)
    if len(hyps) < 2:
        return hyps
    top = max(s for _, s in hyps)
    weight = [math.exp(s - top) for _, s in hyps]
    total = sum(weight)
    gain = [sum(w / total * bleu_plus_one(h, o) for j, ((o, _), w) in enumerate(zip(hyps, weight))
                if j != i) for i, (h, _) in enumerate(hyps)]
    order = sorted(range(len(hyps)), key=lambda i: (-gain[i], i))
    return [hyps[i] for i in order]

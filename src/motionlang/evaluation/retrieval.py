"""The text-to-motion nearest-neighbour baseline: the motion of the training sentence
closest to the query in bag of words.

Sentences are compared after ``datasets.text.tokenize`` (case, punctuation, spelled-out
numbers and the KIT-ML spelling table normalised) as word-count vectors, by cosine
similarity. A bag of words cannot tell "walks, then waves" from "waves, then walks", so
sentences tied on it are ranked by the cosine of their word-pair (bigram) counts; remaining
ties go to the earliest indexed sentence, so a result depends on nothing but the index.
"""
from __future__ import annotations

from collections import Counter
from collections.abc import Iterable

import numpy as np

from motionlang.datasets.text import tokenize
from motionlang.errors import MotionlangError

#: similarities closer than this are equal (float rounding)
TIE = 1e-9


def _cosine(a: Counter, b: Counter) -> float:
    dot = sum(n * b[w] for w, n in a.items() if w in b)
    na, nb = sum(n * n for n in a.values()), sum(n * n for n in b.values())
    return dot / float(np.sqrt(na * nb)) if na and nb else 0.0


def _bigrams(tokens: list[str]) -> Counter:
    return Counter(zip(tokens, tokens[1:]))


class SentenceIndex:
    """Bag-of-words index over ``(key, sentence)`` pairs; a key (e.g. a motion id) may
    appear with several sentences.

    >>> idx = SentenceIndex([("a", "a person walks"), ("b", "a person jumps twice")])
    >>> idx.nearest("someone jumps two times")[0]
    'b'
    """

    def __init__(self, items: Iterable[tuple[str, str]]):
        self.keys, self.sentences = [], []
        for key, sentence in items:
            self.keys.append(key)
            self.sentences.append(sentence)
        if not self.keys:
            raise MotionlangError("the sentence index is empty: no training sentences")
        self.tokens = [tokenize(s) for s in self.sentences]
        counts = [Counter(t) for t in self.tokens]
        self.words = {w: j for j, w in enumerate(sorted(set().union(*counts)))}
        m = np.zeros((len(counts), len(self.words)))
        for i, c in enumerate(counts):
            for w, n in c.items():
                m[i, self.words[w]] = n
        norms = np.linalg.norm(m, axis=1, keepdims=True)
        # an empty sentence has similarity 0 to everything
        self.matrix = m / np.where(norms > 0, norms, 1.0)   # (N, V) unit rows

    def similarities(self, sentence: str) -> np.ndarray:
        """(N,) cosine similarity of ``sentence`` to every indexed sentence, in [0, 1]."""
        q = np.zeros(len(self.words))
        toks = tokenize(sentence)
        for w in toks:
            if w in self.words:
                q[self.words[w]] += 1.0
        # normalised by the query's full length, unknown words included, so that a
        # query of many unknown words is not "close" to anything
        norm = np.sqrt(sum(n * n for n in Counter(toks).values()))
        return self.matrix @ q / norm if norm > 0 else np.zeros(len(self.keys))

    def nearest(self, sentence: str) -> tuple[str, str, float]:
        """(key, indexed sentence, bag-of-words cosine) of the closest indexed sentence."""
        sims = self.similarities(sentence)
        tied = np.flatnonzero(sims >= sims.max() - TIE)
        i = int(tied[0])
        if len(tied) > 1:
            q = _bigrams(tokenize(sentence))
            pairs = np.array([_cosine(q, _bigrams(self.tokens[j])) for j in tied])
            i = int(tied[np.flatnonzero(pairs >= pairs.max() - TIE)[0]])
        return self.keys[i], self.sentences[i], float(sims[i])

"""The text-to-motion nearest-neighbour baseline (issues 5 and 6): the motion of the
training sentence closest to the query in bag of words.

Sentences are compared after ``datasets.text.tokenize`` (case, punctuation, spelled-out
numbers and the KIT-ML spelling table normalised) as word-count vectors, by cosine
similarity. Ties go to the earliest indexed sentence, so a result does not depend on
anything but the index order.
"""
from __future__ import annotations

from collections import Counter
from typing import Iterable

import numpy as np

from motionlang.datasets.text import tokenize
from motionlang.errors import MotionlangError


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
        counts = [Counter(tokenize(s)) for s in self.sentences]
        self.words = {w: j for j, w in enumerate(sorted(set().union(*counts)))}
        m = np.zeros((len(counts), len(self.words)), dtype=np.float32)
        for i, c in enumerate(counts):
            for w, n in c.items():
                m[i, self.words[w]] = n
        norms = np.linalg.norm(m, axis=1, keepdims=True)
        # an empty sentence has similarity 0 to everything
        self.matrix = m / np.where(norms > 0, norms, 1.0)   # (N, V) unit rows

    def similarities(self, sentence: str) -> np.ndarray:
        """(N,) cosine similarity of ``sentence`` to every indexed sentence, in [0, 1]."""
        q = np.zeros(len(self.words), dtype=np.float32)
        toks = tokenize(sentence)
        for w in toks:
            if w in self.words:
                q[self.words[w]] += 1.0
        # normalised by the query's full length, unknown words included, so that a
        # query of many unknown words is not "close" to anything
        norm = np.sqrt(sum(n * n for n in Counter(toks).values()))
        return self.matrix @ q / norm if norm > 0 else np.zeros(len(self.keys), np.float32)

    def nearest(self, sentence: str) -> tuple[str, str, float]:
        """(key, indexed sentence, cosine) of the closest indexed sentence."""
        sims = self.similarities(sentence)
        i = int(np.argmax(sims))   # argmax returns the first of equal values
        return self.keys[i], self.sentences[i], float(sims[i])

"""How long should a generated motion be? A ridge regression from a sentence's word counts to
its motion's length in frames.

The two-stream model decodes for a length it is given, and so does an L2M model with
``progress_input`` (it is told the fraction of its motion done). So that ``motionlang
generate`` gives "a person waves" a short motion and "walks forward eight steps, then turns
around" a long one, their trainers fit this model on the training pairs and the checkpoint
carries it. A motion's length is close to a
sum over its actions, and each action's share is set by its words ("8", "steps", "slowly"),
so a linear model over word counts fits it.
"""
from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from motionlang.datasets.text import tokenize
from motionlang.errors import MotionlangError


@dataclass
class SentenceLength:
    """frames(sentence) = bias + sum over its words of count x weight, clipped to the
    training range [low, high] (frames of the model's rate)."""

    words: list[str]
    weights: list[float]
    bias: float
    low: int
    high: int

    @classmethod
    def fit(cls, sentences: Sequence[str], lengths: Sequence[int], ridge: float = 1.0
            ) -> SentenceLength:
        """Least squares with an L2 penalty ``ridge`` on the word weights (not the bias)."""
        if len(sentences) != len(lengths) or not sentences:
            raise MotionlangError(f"need as many lengths as sentences, at least one; got "
                                  f"{len(sentences)} sentences and {len(lengths)} lengths")
        counts = [Counter(tokenize(s)) for s in sentences]
        words = sorted(set().union(*counts))
        col = {w: j for j, w in enumerate(words)}
        x = np.zeros((len(counts), len(words) + 1))
        x[:, -1] = 1.0                                   # bias column
        for i, c in enumerate(counts):
            for w, n in c.items():
                x[i, col[w]] = n
        y = np.asarray(lengths, dtype=np.float64)
        # the penalty as extra rows sqrt(ridge) * I (bias column 0) under least squares
        # (with ridge 0, the minimum-norm solution among the equally good ones)
        penalty = np.sqrt(ridge) * np.eye(len(words), len(words) + 1)
        beta = np.linalg.lstsq(np.vstack([x, penalty]),
                               np.concatenate([y, np.zeros(len(words))]), rcond=None)[0]
        return cls(words, [float(b) for b in beta[:-1]], float(beta[-1]),
                   int(y.min()), int(y.max()))

    @classmethod
    def from_items(cls, items: Sequence[dict]) -> SentenceLength:
        """Fitted on training items ``{"sentence", "motion": (T, F)}`` (one per sentence)."""
        return cls.fit([it["sentence"] for it in items], [len(it["motion"]) for it in items])

    @cached_property
    def _weight(self) -> dict[str, float]:
        return dict(zip(self.words, self.weights))

    def frames(self, sentence: str) -> int:
        """Predicted length of ``sentence``'s motion in frames (unknown words count 0)."""
        guess = self.bias + sum(self._weight.get(w, 0.0) for w in tokenize(sentence))
        return int(np.clip(round(guess), self.low, self.high))

    def to_dict(self) -> dict:
        # plain Python types: checkpoints load with torch.load(weights_only=True)
        return {"words": [str(w) for w in self.words],
                "weights": [float(w) for w in self.weights], "bias": float(self.bias),
                "low": int(self.low), "high": int(self.high)}

    @classmethod
    def from_dict(cls, d: dict) -> SentenceLength:
        return cls(list(d["words"]), [float(w) for w in d["weights"]], float(d["bias"]),
                   int(d["low"]), int(d["high"]))

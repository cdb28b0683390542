"""The bag-of-words sentence index of the text-to-motion nearest-neighbour baseline, and the
re-timing of a retrieved motion (``models.t2m.stretch``)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.retrieval import SentenceIndex
from motionlang.models.t2m import interp_frames, stretch


def test_cosine_by_hand():
    idx = SentenceIndex([("a", "A person walks."), ("b", "a person walks forward"),
                         ("c", "someone waves")])
    # tokens: "a person walks" and "a person walks forward": 3 shared words,
    # norms sqrt(3) and sqrt(4) -> 3 / (2 sqrt 3)
    sims = idx.similarities("a person walks")
    np.testing.assert_allclose(sims, [1.0, 3 / (2 * math.sqrt(3)), 0.0], atol=1e-6)
    assert idx.nearest("a person walks") == ("a", "A person walks.", pytest.approx(1.0))
    assert idx.nearest("someone waves twice")[0] == "c"
    # normalised like every sentence: spelled-out numbers and case
    idx2 = SentenceIndex([("x", "walks 4 steps"), ("y", "walks 2 steps")])
    assert idx2.nearest("Walks four steps")[0] == "x"


def test_counts_ties_and_unknown_words():
    idx = SentenceIndex([("a", "wave wave"), ("b", "wave jump"), ("c", "wave jump")])
    # repeated words count: "wave wave" vs "wave" cosine 1, "wave jump" vs "wave" 1/sqrt 2
    assert idx.nearest("wave")[0] == "a"
    # a tie goes to the earliest indexed sentence
    assert idx.nearest("jump wave")[0] == "b"
    # unknown words lower the similarity (the query's norm counts them) but change no rank
    sims = idx.similarities("jump zzz")
    np.testing.assert_allclose(sims, [0.0, 0.5, 0.5], atol=1e-6)
    # nothing in common: all 0, the first sentence
    assert idx.nearest("zzz") == ("a", "wave wave", 0.0)
    assert idx.nearest("") == ("a", "wave wave", 0.0)


def test_word_order_breaks_bag_of_words_ties():
    idx = SentenceIndex([("ab", "a person walks forward then waves"),
                         ("ba", "a person waves then walks forward"),
                         ("ab2", "a person walks forward then waves")])
    key, _, cos = idx.nearest("a person waves, then walks forward")
    assert key == "ba" and cos == pytest.approx(1.0)
    assert idx.nearest("A person walks forward, then waves.")[0] == "ab"   # first of equals
    # equal bags that differ by a rounding step in float32 still tie
    idx2 = SentenceIndex([("x", "walk walk wave wave"), ("y", "walk wave")])
    assert idx2.nearest("wave walk")[0] == "x"


def test_empty_index_is_an_error():
    with pytest.raises(MotionlangError, match="empty"):
        SentenceIndex([])


def test_stretch_and_interp():
    p = np.arange(5, dtype=float)[:, None, None] * np.ones((1, 2, 3))   # (5, 2, 3)
    s = stretch(p, 9)
    assert s.shape == (9, 2, 3)
    np.testing.assert_allclose(s[:, 0, 0], np.arange(9) / 2)   # halfway frames in between
    np.testing.assert_allclose(stretch(p, 3)[:, 1, 2], [0, 2, 4])
    np.testing.assert_allclose(stretch(p[:1], 4), np.repeat(p[:1], 4, axis=0))
    # held constant outside the source times
    out = interp_frames(p, np.array([0.0, 1, 2, 3, 4]), np.array([-1.0, 0.5, 9]))
    np.testing.assert_allclose(out[:, 0, 0], [0.0, 0.5, 4.0])

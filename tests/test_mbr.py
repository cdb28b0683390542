"""Minimum Bayes risk ordering of description beams (models.seq2seq.decode.mbr), worked by hand."""
from __future__ import annotations

import math

import pytest

from motionlang.models.seq2seq.decode.mbr import bleu_plus_one, mbr_rank


def test_bleu_plus_one_by_hand():
    # matches 2, 1, 0, 0 of 3, 2, 1, 0 n-grams; add one from 2-grams on
    assert bleu_plus_one("a b c", "a b d") == pytest.approx(
        ((2 / 3) * (2 / 3) * (1 / 2) * (1 / 1)) ** 0.25)
    assert bleu_plus_one("a b c d", "a b c d") == pytest.approx(1.0)
    # a hypothesis shorter than the reference pays the brevity penalty
    short = bleu_plus_one("a b", "a b c d")
    assert short == pytest.approx(math.exp(1 - 4 / 2) * ((3 / 3) * (2 / 2) * 1 * 1) ** 0.25)
    assert bleu_plus_one("", "a b") == 0.0
    assert bleu_plus_one("x y", "a b") == 0.0              # no shared word
    assert bleu_plus_one("a x", "a b") == pytest.approx((1 / 2 * 1 / 2) ** 0.25)


def test_mbr_puts_the_consensus_first():
    beam = [("a person waves", -1.0),                      # likeliest, shares least
            ("a person waves the left hand", -1.5),
            ("someone waves the left hand", -1.6),
            ("a person waves with the left hand", -1.7)]
    ranked = mbr_rank(beam)
    assert sorted(ranked) == sorted(beam)                  # same pairs, scores kept
    assert ranked[0] == ("a person waves the left hand", -1.5)
    assert ranked[-1] == ("a person waves", -1.0)
    # two sentences of one length agree with each other equally: the likelier stays first
    two = [("a person walks forward", -1.0), ("a person walks backward", -5.0)]
    assert mbr_rank(two) == two and mbr_rank(two[::-1]) == two[::-1]
    assert mbr_rank(beam[:1]) == beam[:1] and mbr_rank([]) == []

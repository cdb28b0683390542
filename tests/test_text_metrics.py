"""Text metrics on examples worked out by hand."""
from __future__ import annotations

import math

import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics import text as tm


def test_bleu_of_one_sentence_by_hand():
    # p1..p4 = 4/5, 3/4, 2/3, 1/2, equal lengths -> no brevity penalty.
    got = tm.corpus_bleu([["a b c d e"]], ["a b c d f"])
    assert got == pytest.approx((0.8 * 0.75 * (2 / 3) * 0.5) ** 0.25, rel=1e-9)
    assert tm.corpus_bleu([["a b c d e"]], ["a b c d e"]) == pytest.approx(1.0)


def test_corpus_bleu_sums_counts_and_uses_all_references():
    refs = [["a b c d"], ["p r s"]]
    hyps = ["a b c d", "p q"]
    # matches: 1-grams 4+1 of 6, 2-grams 3+0 of 4, 3-grams 2+0 of 2+1, 4-grams 1+0 of 1+1
    # (nltk counts a sentence too short for an n-gram order as 0 matches out of 1);
    # hypothesis length 6 vs reference length 4 + 3 = 7 -> BP = exp(1 - 7/6).
    want = math.exp(1 - 7 / 6) * ((5 / 6) * (3 / 4) * (2 / 3) * (1 / 2)) ** 0.25
    assert tm.corpus_bleu(refs, hyps) == pytest.approx(want, rel=1e-9)
    # A second reference "p q" of length 2: closest length 2 -> r = 6, no penalty, and
    # its bigram "p q" now matches: p1 = 6/6, p2 = 4/4.
    refs2 = [["a b c d"], ["p r s", "p q"]]
    assert tm.corpus_bleu(refs2, hyps) == pytest.approx(((2 / 3) * (1 / 2)) ** 0.25, rel=1e-9)
    # averaging sentence scores would give something else
    assert tm.corpus_bleu(refs, hyps) != pytest.approx(
        (tm.corpus_bleu(refs[:1], hyps[:1]) + tm.corpus_bleu(refs[1:], hyps[1:])) / 2)


def test_bleu1_clips_counts():
    # "the the the" against "the cat": clipped unigram matches 1 of 3; lengths 3 vs 2 -> BP 1.
    assert tm.bleu1([["the cat"]], ["the the the"]) == pytest.approx(1 / 3)
    # short hypothesis: 1/1 precision, BP = exp(1 - 2/1)
    assert tm.bleu1([["the cat"]], ["cat"]) == pytest.approx(math.exp(-1.0))


def test_rouge_l_by_hand():
    # LCS("a b c d", "a c d e") = "a c d": P = R = 3/4 -> F = 3/4; the best reference counts.
    assert tm.rouge_l([["a c d e"]], ["a b c d"]) == pytest.approx(0.75)
    assert tm.rouge_l([["x y", "a c d e"]], ["a b c d"]) == pytest.approx(0.75)
    # mean over items: second item has no overlap
    assert tm.rouge_l([["a c d e"], ["u v"]], ["a b c d", "w"]) == pytest.approx(0.375)


def test_cider_ranks_exact_matches_first():
    pytest.importorskip("pycocoevalcap")
    refs = [["a person walks forward"], ["a person waves the left hand"],
            ["someone kicks with the right foot"]]
    perfect = tm.cider(refs, [r[0] for r in refs])
    partial = tm.cider(refs, ["a person walks", "a person waves", "someone kicks"])
    assert perfect > partial > 0


def test_bleu_by_rank_and_correlation():
    refs = [["a person walks forward slowly"], ["a person waves the left hand"]]
    ranked = [["a person walks forward slowly", "a person walks forward", "a man jumps"],
              ["a person waves the left hand", "a person waves the hand", "someone sits"]]
    by_rank = tm.bleu_by_rank(refs, ranked)
    assert by_rank[0] == pytest.approx(1.0)
    assert by_rank[0] > by_rank[1] >= by_rank[2]
    rho = tm.rank_bleu_correlation(refs, ranked)
    assert rho < -0.9                            # BLEU falls with rank in both items
    assert tm.rank_bleu_correlation(refs, [h[::-1] for h in ranked]) > 0.9
    assert math.isnan(tm.rank_bleu_correlation(refs, [["x", "y"], ["z", "w"]]))


def test_bad_inputs_raise_motionlang_errors():
    with pytest.raises(MotionlangError, match="2 hypotheses but 1"):
        tm.corpus_bleu([["a"]], ["a", "b"])
    with pytest.raises(MotionlangError, match="at least one reference"):
        tm.rouge_l([[]], ["a"])
    with pytest.raises(MotionlangError, match="same number"):
        tm.bleu_by_rank([["a"], ["b"]], [["a", "b"], ["c"]])

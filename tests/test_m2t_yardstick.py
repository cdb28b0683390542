"""The motion-to-text half of the yardstick (``evaluation.t2m.m2t``) on values worked out by
hand, with a stand-in evaluator whose embeddings are known."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.t2m.m2t import (
    m2t_table,
    nearest_captions,
    other_references,
    text_measures,
)
from motionlang.evaluation.t2m.plots import plot_yardstick

WORDS = ["walks", "runs", "jumps", "waves"]


class KeywordEvaluator:
    """Text: one-hot of the first known verb; motion: one-hot of the row's first value."""

    def embed_texts(self, captions, tokens=None):
        out = np.zeros((len(captions), len(WORDS)))
        for i, c in enumerate(captions):
            hit = [k for k, w in enumerate(WORDS) if w in c.split()]
            if hit:
                out[i, hit[0]] = 1.0
        return out

    def embed_motions(self, motions):
        return np.stack([np.eye(len(WORDS))[int(np.asarray(m)[0, 0])] for m in motions])


def pair(i: int, verb: int) -> dict:
    rows = np.full((3, 2), float(verb))
    rows[:, 1] = np.arange(3) * (verb + 1)   # the second value moves at a verb's own speed
    return {"id": f"m{i}", "motion": rows, "caption": f"a person {WORDS[verb]}"}


def test_other_references_drop_one_copy_of_the_own_caption():
    refs = [["A person walks.", "someone walks", "a person walks"], ["a man runs"]]
    assert other_references(refs, ["a person walks", "a man runs"]) == [
        ["someone walks", "a person walks"], []]


def test_text_measures_skip_motions_without_references():
    got = text_measures([["a person walks forward"], []], ["a person walks forward", "anything"])
    assert got["BLEU@1"] == pytest.approx(1.0) and got["BLEU@4"] == pytest.approx(1.0)
    assert got["ROUGE-L"] == pytest.approx(1.0)
    assert text_measures([[], []], ["a", "b"]) == {}


def test_nearest_captions_pick_the_training_motion_of_the_same_statistics():
    train = [pair(10 + v, v) for v in range(4)]
    train.append({**pair(99, 1), "caption": "a second caption of m11", "id": "m11"})
    tests = [pair(0, 2), pair(1, 0)]
    assert nearest_captions(train, tests) == ["a person jumps", "a person walks"]


def test_m2t_table_ground_truth_is_perfect_and_a_wrong_description_is_not():
    pairs = [pair(i, i) for i in range(4)]   # one batch of 4 motions, 4 different verbs
    refs = [[p["caption"], p["caption"].replace("a person", "someone")] for p in pairs]
    train = [pair(20 + v, v) for v in range(4)]
    wrong = [f"a person {WORDS[(i + 1) % 4]}" for i in range(4)]
    table, counted = m2t_table(KeywordEvaluator(), pairs, refs, train, {"wrong": wrong},
                               repeats=3, batch_size=4)
    assert counted == 4 and list(table) == ["ground truth", "nearest neighbour", "wrong"]
    # every description ranks its motion first among 4 distinct ones: R-precision 1, MM-Dist 0
    truth = table["ground truth"]
    assert truth["R-precision top-1"][0] == pytest.approx(1.0)
    assert truth["MM-Dist"][0] == pytest.approx(0.0)
    # "a person walks" against "someone walks": 1 of 3 words (BLEU@1 with brevity 1)
    assert truth["BLEU@1"] == pytest.approx(1 / 3)
    assert table["nearest neighbour"]["R-precision top-1"][0] == pytest.approx(1.0)
    # a wrong verb: its text is another motion's; the own motion is at sqrt(2) like the others
    assert table["wrong"]["MM-Dist"][0] == pytest.approx(np.sqrt(2))
    assert table["wrong"]["R-precision top-1"][0] == 0.0


def test_m2t_table_checks_its_inputs():
    pairs = [pair(i, i % 4) for i in range(4)]
    with pytest.raises(MotionlangError, match="at least 32 pairs"):
        m2t_table(KeywordEvaluator(), pairs, [["x"]] * 4, [pair(9, 0)])
    with pytest.raises(MotionlangError, match="3 reference lists for 4 pairs"):
        m2t_table(KeywordEvaluator(), pairs, [["x"]] * 3, [pair(9, 0)], batch_size=4)
    with pytest.raises(MotionlangError, match="m2l: 2 descriptions for 4 motions"):
        m2t_table(KeywordEvaluator(), pairs, [["x"]] * 4, [pair(9, 0)], {"m2l": ["a", "b"]},
                  batch_size=4, repeats=1)


def test_plot_yardstick_writes_one_png(tmp_path):
    t2m = {"ground truth": {"R-precision top-3": (0.9, 0.01), "FID": (0.1, 0.0)},
           "still": {"R-precision top-3": (0.1, 0.01), "FID": (300.0, 0.0)}}
    m2t = {"ground truth": {"R-precision top-3": (0.9, 0.0), "BLEU@4": 0.5}}
    out = tmp_path / "t.png"
    plot_yardstick(t2m, out, m2t, title="test")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.png"]


def test_r_precision_miss_scores_an_evaluator_on_one_caption_per_motion():
    from motionlang.evaluation.t2m.yardstick import r_precision_miss
    items = [pair(i, i) for i in range(4)]
    items += [{**p, "caption": p["caption"] + " again"} for p in items]   # 2 captions each
    miss = r_precision_miss(items, batch_size=4, top=1)
    assert miss(KeywordEvaluator()) == 0.0   # every caption finds its own motion first
    assert r_precision_miss(items, batch_size=32) is None   # fewer motions than a batch

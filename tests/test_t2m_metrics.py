"""Text-to-motion metrics on values worked out by hand, and against brute force."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.t2m import (
    activation_statistics,
    diversity,
    euclidean_distance_matrix,
    fid,
    frechet_distance,
    hit_ranks,
    mean_interval,
    mm_dist,
    multimodality,
    r_precision,
    repeat,
    retrieval_metrics,
    retrieval_ranks,
    retrieval_scores,
    top_k_hits,
)


def test_distance_matrix_by_hand_and_brute_force():
    a, b = [[0, 0], [3, 4]], [[0, 0], [6, 8], [3, 0]]
    assert euclidean_distance_matrix(a, b) == pytest.approx(np.array([[0, 10, 3], [5, 5, 4]]))
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(7, 5)), rng.normal(size=(4, 5))
    brute = [[np.sqrt(((u - v) ** 2).sum()) for v in y] for u in x]
    assert euclidean_distance_matrix(x, y) == pytest.approx(np.array(brute))
    assert (euclidean_distance_matrix(x, x).diagonal() >= 0).all()   # never NaN from rounding


def test_top_k_hits_by_hand():
    d = [[1, 0, 3], [2, 1, 0], [0.5, 0.2, 0.1]]
    assert top_k_hits(d, 3).tolist() == [[False, True, True], [False, True, True],
                                         [True, True, True]]


def test_r_precision_and_mm_dist_by_hand():
    """Batches of 2: (0, 1) both find their motion first; (10, 11) both second; the fifth
    pair is an incomplete batch and does not count."""
    text = [[0], [1], [10], [11], [100]]
    motion = [[0.2], [0.7], [11], [10], [0]]
    assert r_precision(text, motion, top_k=2, batch_size=2) == pytest.approx([0.5, 1.0])
    assert mm_dist(text, motion, batch_size=2) == pytest.approx((0.2 + 0.3 + 1 + 1) / 4)


def test_r_precision_drops_the_last_batch_and_matches_brute_force():
    rng = np.random.default_rng(1)
    t = rng.normal(size=(40, 8))
    m = t.copy()
    m[32:] = rng.normal(size=(8, 8)) * 10        # bad pairs, all in the dropped batch
    assert r_precision(t, m).tolist() == [1.0, 1.0, 1.0]
    t, m = rng.normal(size=(96, 4)), rng.normal(size=(96, 4))
    hits = np.zeros(3)
    for s in range(0, 96, 32):
        for i in range(32):
            d = [np.linalg.norm(t[s + i] - m[s + j]) for j in range(32)]
            rank = sum(x < d[i] for x in d)
            hits += [rank < k for k in (1, 2, 3)]
    assert r_precision(t, m) == pytest.approx(hits / 96)
    shuffled = r_precision(t, m, rng=3)
    assert shuffled.tolist() == r_precision(t, m, rng=3).tolist()
    assert 0 <= shuffled[0] <= shuffled[1] <= shuffled[2] <= 1
    with pytest.raises(MotionlangError, match="full batch of 32"):
        r_precision(t[:31], m[:31])


def test_frechet_distance_by_hand():
    assert frechet_distance([0], [[1]], [3], [[4]]) == pytest.approx(9 + 1 + 4 - 2 * 2)
    # diagonal covariances: |d|^2 + sum (sqrt(a) - sqrt(b))^2 = 2 + (1 - 2)^2 + (3 - 1)^2
    assert frechet_distance([0, 0], np.diag([1, 9]), [1, 1], np.diag([4, 1])) == \
        pytest.approx(7)
    # from embeddings: means 1 and 3, variances (N - 1) 2 and 8: 4 + 2 + 8 - 2 * 4
    assert fid([[0], [2]], [[1], [5]]) == pytest.approx(6)
    singular = np.diag([1.0, 0.0])
    assert frechet_distance([0, 0], singular, [0, 0], singular) == pytest.approx(0, abs=1e-6)


def test_fid_against_eigenvalues():
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=(200, 5)), rng.normal(size=(150, 5)) @ rng.normal(size=(5, 5))
    (mu1, s1), (mu2, s2) = activation_statistics(a), activation_statistics(b)
    root_trace = np.sqrt(np.clip(np.linalg.eigvals(s1 @ s2).real, 0, None)).sum()
    want = ((mu1 - mu2) ** 2).sum() + np.trace(s1) + np.trace(s2) - 2 * root_trace
    assert fid(a, b) == pytest.approx(want, rel=1e-8)
    assert fid(a, a) == pytest.approx(0, abs=1e-8)


def test_fid_of_fewer_samples_than_dimensions_takes_an_offset_and_says_so(caplog):
    # 20 samples in 128 dimensions: sqrtm's root of the singular product has an imaginary
    # diagonal beyond the public code's tolerance for this draw (which stopped with an error)
    rng = np.random.default_rng(192)
    a, b = rng.normal(size=(20, 128)) * 3, rng.normal(size=(20, 128)) * 3 + 0.5
    (mu1, s1), (mu2, s2) = activation_statistics(a), activation_statistics(b)
    root_trace = np.sqrt(np.clip(np.linalg.eigvals(s1 @ s2).real, 0, None)).sum()
    want = ((mu1 - mu2) ** 2).sum() + np.trace(s1) + np.trace(s2) - 2 * root_trace
    with caplog.at_level("WARNING"):
        got = fid(a, b)
    assert got == pytest.approx(want, rel=1e-3)
    assert "singular" in caplog.text and "added to the diagonals" in caplog.text
    with pytest.raises(MotionlangError, match="imaginary part"):   # no offset at all
        frechet_distance(mu1, s1, mu2, s2, eps=0.0)
    caplog.clear()
    with caplog.at_level("WARNING"):   # a well-conditioned pair needs no offset: no warning
        fid(rng.normal(size=(200, 5)), rng.normal(size=(200, 5)))
    assert caplog.text == ""


def test_diversity_and_multimodality():
    assert diversity(np.ones((5, 3)), times=4) == 0.0
    x = np.arange(6.0)[:, None]
    g = np.random.default_rng(7)
    f, s = g.choice(6, 5, replace=False), g.choice(6, 5, replace=False)
    assert diversity(x, times=5, rng=7) == pytest.approx(np.abs(x[f] - x[s]).mean())
    with pytest.raises(MotionlangError, match="N > 300"):
        diversity(np.zeros((300, 2)))
    same = np.repeat(np.arange(4.0)[:, None, None], 12, axis=1)      # (4 texts, 12, 1)
    assert multimodality(same, times=10) == 0.0
    y = np.random.default_rng(0).normal(size=(3, 12, 2))
    g = np.random.default_rng(5)
    f, s = g.choice(12, 10, replace=False), g.choice(12, 10, replace=False)
    brute = np.mean([np.linalg.norm(y[i, f[k]] - y[i, s[k]]) for i in range(3)
                     for k in range(10)])
    assert multimodality(y, times=10, rng=5) == pytest.approx(brute)
    with pytest.raises(MotionlangError, match="S > 10"):
        multimodality(np.zeros((2, 10, 3)))


def test_retrieval_ranks_by_hand():
    sims = [[1, 1, 0], [0.5, 0.2, 0.9], [0, 0, 1]]
    assert retrieval_ranks(sims).tolist() == [0.5, 2.0, 0.0]        # a tie shares 0 and 1
    same_text = np.array([[1, 0, 0], [0, 1, 1], [0, 1, 1]])          # texts 1 and 2 alike
    assert retrieval_ranks(sims, same_text, threshold=0.95).tolist() == [0.5, 0.0, 0.0]


def test_retrieval_scores_with_hits_by_hand():
    """Two texts, three motions. Text 0 counts motions 0 and 1 as its pair: its best hit
    (0.9) ties with motion 2, rank 0.5. Text 1 counts motions 1 and 2: its two hits tie at
    0.8, which costs neither, rank 0. Motion 2 as a query: text 0 (0.9, not a hit) is above
    its hit text 1 (0.8), rank 1."""
    sims = [[0.9, 0.5, 0.9], [0.1, 0.8, 0.8]]
    hits = [[True, True, False], [False, True, True]]
    assert hit_ranks(sims, hits).tolist() == [0.5, 0.0]
    got = retrieval_scores(sims, hits, ks=(1, 2))
    assert got == pytest.approx({"t2m/R01": 100.0, "t2m/R02": 100.0, "t2m/MedR": 1.25,
                                 "m2t/R01": 200 / 3, "m2t/R02": 100.0, "m2t/MedR": 1.0})
    # the default hits are the diagonal: the same ranks as retrieval_ranks
    square = np.round(np.random.default_rng(2).uniform(size=(12, 12)), 1)
    scores = retrieval_scores(square, ks=(1, 5))
    ranks = retrieval_ranks(square)
    assert scores["t2m/R05"] == pytest.approx(100 * np.mean(ranks < 5))
    assert scores["t2m/MedR"] == pytest.approx(np.median(ranks) + 1)
    with pytest.raises(MotionlangError, match="query 1 has no hit"):
        hit_ranks(sims, [[True, False, False], [False, False, False]])
    with pytest.raises(MotionlangError, match="one"):
        hit_ranks(sims, [[True]])


def _tmr_like_ranks(sims):
    """Brute force: sort each row, average the positions holding the pair's value."""
    out = []
    for i, row in enumerate(np.asarray(sims)):
        ordered = sorted(row, reverse=True)
        out.append(np.mean([k for k, v in enumerate(ordered) if v == row[i]]))
    return np.array(out)


def test_retrieval_against_brute_force_and_by_hand():
    sims = np.round(np.random.default_rng(4).uniform(size=(30, 30)), 1)     # many ties
    assert retrieval_ranks(sims) == pytest.approx(_tmr_like_ranks(sims))
    text, motion = [[1, 0], [0, 1], [1, 1]], [[1, 0], [1, 1], [0, 1]]
    got = retrieval_metrics(text, motion, ks=(1, 2))
    # text ranks: 0; 1 (motion 2 is closer); 1.5 (motion 1 closer, tie with motion 0)
    assert got["t2m/R01"] == pytest.approx(100 / 3) and got["t2m/R02"] == 100.0
    assert got["t2m/MedR"] == 2.0
    assert got["m2t/R01"] == pytest.approx(100 / 3) and got["m2t/MedR"] == 2.0
    rng = np.random.default_rng(6)
    t, m = rng.normal(size=(8, 3)), rng.normal(size=(8, 3))
    halves = [retrieval_metrics(t[:4], m[:4]), retrieval_metrics(t[4:], m[4:])]
    assert retrieval_metrics(t, m, batch_size=4) == pytest.approx(
        {k: (halves[0][k] + halves[1][k]) / 2 for k in halves[0]})
    e = np.random.default_rng(0).normal(size=(50, 16))
    perfect = retrieval_metrics(e, e * 3.0)
    assert perfect["t2m/R01"] == perfect["m2t/R10"] == 100.0 and perfect["t2m/MedR"] == 1.0


def test_mean_interval_and_repeat():
    half = 1.96 * np.sqrt(1.25) / 2                  # population std of 1..4, n = 4
    assert mean_interval([1, 2, 3, 4]) == pytest.approx((2.5, half))
    assert repeat(lambda i: float(i + 1), n=4) == pytest.approx((2.5, half))
    d = repeat(lambda i: {"fid": 1.0, "r": np.array([i, 2 * i])}, n=4)
    assert d["fid"] == pytest.approx((1.0, 0.0))
    mean, h = d["r"]
    assert mean.tolist() == [1.5, 3.0] and h == pytest.approx([half, 2 * half])
    with pytest.raises(MotionlangError):
        mean_interval([])

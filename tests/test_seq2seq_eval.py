"""Seq2seq evaluation: M2L scores by rank, nearest-neighbour baseline, L2M round trip."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from helpers.seq2seq import WORDS, items, tiny
from motionlang.datasets.text import normalize
from motionlang.errors import MotionlangError
from motionlang.evaluation import seq2seq as ev
from motionlang.training.collate import collate_pairs
from motionlang.training.trainer import TrainConfig, Trainer

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    data = items()
    model = tiny("m2l", False)
    Trainer(model, data, collate_pairs, TrainConfig(
        epochs=60, batch_size=4, lr=1e-2, out_dir=str(tmp_path_factory.mktemp("run")),
        plot=False, progress=False)).fit()
    frames = {f"m{i}": d["motion"] for i, d in enumerate(data)}
    refs = {f"m{i}": [" ".join(WORDS[t] for t in d["tokens"][1:-1])] for i, d in enumerate(data)}
    return model.eval(), frames, refs


def test_m2l_scores_of_a_model_that_memorised(trained):
    model, frames, refs = trained
    res = ev.evaluate_m2l(model, frames, refs, width=3)
    assert res["n"] == 8 and len(res["bleu_by_rank"]) == 3
    assert res["bleu"] == pytest.approx(1.0) and res["bleu_by_rank"][0] == pytest.approx(1.0)
    assert res["bleu_by_rank"][1] < 1.0                  # other hypotheses differ
    assert res["rouge_l"] == pytest.approx(1.0) and res["bleu1"] == pytest.approx(1.0)
    assert res["rank_bleu_spearman"] < 0
    assert res["examples"][0]["hypotheses"][0] == res["examples"][0]["references"][0]


def test_nearest_neighbour_baseline():
    rng = np.random.default_rng(0)
    train = {"a": rng.normal(0, 1, (10, 3)), "b": rng.normal(5, 1, (12, 3)),
             "c": rng.normal(-5, 3, (8, 3))}
    refs = {"a": ["A person Walks.", "x"], "b": ["someone jumps"], "c": ["a kick"]}
    query = {"q1": rng.normal(5, 1, (20, 3)), "q2": rng.normal(-5, 3, (9, 3))}
    nn = ev.nearest_neighbour_descriptions(train, refs, query)
    assert nn == {"q1": "someone jumps", "q2": "a kick"}
    res = ev.evaluate_nn_baseline(train, refs, query, {"q1": ["someone jumps"],
                                                       "q2": ["a person kicks"]})
    assert res["n"] == 2 and 0 < res["bleu1"] < 1 and 0 < res["rouge_l"] < 1


def test_round_trip_and_table(trained):
    m2l, frames, refs = trained
    l2m = tiny("l2m", False)
    l2m.vocab = WORDS
    res = ev.evaluate_round_trip(l2m, m2l, refs, m2l_bleu=0.5, max_frames=8)
    assert res["n_sentences"] == 8
    assert res["relative"] == pytest.approx(res["bleu"] / 0.5)
    assert math.isnan(ev.evaluate_round_trip(l2m, m2l, {"m0": refs["m0"]}, 0.0,
                                             max_frames=4)["relative"])
    # the baseline: the motion of the closest training sentence. Each test sentence is also
    # a training sentence, so it retrieves a motion the memorising M2L describes with it
    from motionlang.evaluation.retrieval import SentenceIndex
    index = SentenceIndex((i, s) for i in sorted(refs) for s in refs[i])
    nn = ev.evaluate_round_trip_nn(index, frames, m2l, refs, m2l_bleu=0.5)
    assert nn["n_sentences"] == 8 and nn["bleu"] == pytest.approx(1.0)
    assert nn["relative"] == pytest.approx(2.0)
    assert [d[2] for d in nn["descriptions"]] == [normalize(refs[i][0]) for i in sorted(refs)]
    # a motion the M2L describes otherwise: only the retrieved frames count
    swapped = ev.evaluate_round_trip_nn(index, {"m0": frames["m1"], "m1": frames["m0"]}, m2l,
                                        {"m0": refs["m0"]}, m2l_bleu=0.5)
    assert swapped["descriptions"][0][2] == normalize(refs["m1"][0]) and swapped["bleu"] < 0.5
    table = ev.markdown_table({"M2L": {"bleu": 0.5, "bleu1": 0.7}, "NN": {"bleu": 0.25}})
    assert table.splitlines()[0] == "| | bleu | bleu1 |"
    assert "| NN | 0.250 |  |" in table


def test_parameter_accuracy_on_hand_made_descriptions():
    from motionlang.datasets.synth import generate_sample
    sample = generate_sample(3, 0)
    truth = {"a": sample.primitives, "b": sample.primitives}
    texts = {"a": sample.annotations[0], "b": "a person bows"}
    acc = ev.parameter_accuracy(texts, truth)
    assert acc["n"] == 2
    # the corpus's own sentence states only true parameters
    own = ev.parameter_accuracy({"a": sample.annotations[0]}, truth)
    for f in ("side", "count", "direction", "speed"):
        assert own[f + "_stated"] == 0 or own[f] == 1.0
    if [p.action for p in sample.primitives] != ["bow"]:
        assert acc["actions_match"] <= 0.5


def test_context_tsne_keeps_separated_clusters_apart(tmp_path):
    pytest.importorskip("sklearn")
    from motionlang.evaluation.context_tsne import plot_context_tsne, tsne_2d
    rng = np.random.default_rng(0)
    vec = np.concatenate([rng.normal(0, 0.1, (15, 8)), rng.normal(5, 0.1, (15, 8))])
    xy = tsne_2d(vec)
    a, b = xy[:15], xy[15:]
    spread = max(np.linalg.norm(a - a.mean(0), axis=1).max(),
                 np.linalg.norm(b - b.mean(0), axis=1).max())
    assert np.linalg.norm(a.mean(0) - b.mean(0)) > 2 * spread
    path = plot_context_tsne({"m": (vec, ["x"] * 15 + ["y"] * 15)}, tmp_path / "t.png")
    assert path.stat().st_size > 1000


def test_actions_named_by_place_on_hand_made_descriptions():
    from motionlang.datasets.synth import Primitive
    truths = {"m1": [Primitive("walk"), Primitive("wave"), Primitive("kick")],
              "m2": [Primitive("bow")]}
    descriptions = [("m1", "s", "a person walks forward and then waves with the left hand"),
                    ("m1", "s", "a person kicks with the right foot"),   # the last one only
                    ("m2", "s", "a person waves"),                       # not the bow
                    ("m2", "s", "a person bows")]
    got = ev.actions_named(descriptions, truths)
    # first (walk): named 1 of 2; later (wave, kick) x 2: 1 + 1 of 4; only (bow): 1 of 2
    assert got == {"first": 0.5, "n_first": 2, "later": 0.5, "n_later": 4,
                   "only": 0.5, "n_only": 2}
    empty = ev.actions_named([("m2", "s", "a person bows")], truths)
    assert empty["only"] == 1.0 and empty["n_first"] == 0 and empty["first"] != empty["first"]


def test_sentence_log_probs_equal_stepwise_decoding_in_any_batch():
    from motionlang.models.seq2seq.decode.rerank import sentence_log_probs
    rng = np.random.default_rng(3)
    for attention in (False, True):
        m2l = tiny("m2l", attention).eval()
        motions = [rng.normal(size=(T, m2l.config.n_features)).astype(np.float32)
                   for T in (5, 9, 7)]
        tokens = [1, 4, 6, 5, 2]
        together = sentence_log_probs(m2l, motions, tokens)
        for m, score in zip(motions, together):
            # one motion alone, word by word through the decoding step beam search uses
            with torch.no_grad():
                state = m2l.encode(torch.as_tensor(m)[None], torch.tensor([len(m)]))
                total = 0.0
                for prev, nxt in zip(tokens[:-1], tokens[1:]):
                    logp, state = m2l.step(state, torch.tensor([prev]))
                    total += float(logp[0, nxt])
            assert score == pytest.approx(total, abs=1e-4)
        assert len(set(np.round(together, 4))) == 3          # the motions matter
        # text goes through the model's vocabulary: the same ids, the same scores
        assert sentence_log_probs(m2l, motions, "w4 w6 w5") == pytest.approx(together)


def test_rerank_puts_the_motion_the_sentence_describes_first(trained):
    from motionlang.models.seq2seq.decode.rerank import rerank
    m2l, frames, refs = trained
    up, down = frames["m0"], frames["m1"]             # rising / falling first feature
    for sentence, want in ((refs["m0"][0], up), (refs["m1"][0], down)):
        # the L2M's own ranking (second item) says the other one: the M2L decides
        other = down if want is up else up
        ranked = rerank([(other, 0.0), (want, -9.0)], m2l, sentence)
        assert ranked[0][0] is want and ranked[0][1] == -9.0
        assert ranked[0][2] > ranked[1][2]


class StubFeatures:
    """A feature set of identity frames: what the reranking code needs of one."""
    kind, fps = "stub", 10.0

    def __init__(self, dim: int):
        self.dim, self.names = dim, [f"f{i}" for i in range(dim)]

    def to_dict(self) -> dict:
        return {"kind": self.kind, "names": self.names}

    def decode(self, x):
        return x


def _same_features(*models):
    for m in models:
        m.features = StubFeatures(m.config.n_features)


def test_round_trip_describes_the_motion_the_reranker_puts_first(trained, monkeypatch):
    import copy
    m2l, frames, refs = trained
    l2m = tiny("l2m", False)
    l2m.vocab = WORDS
    ranker = copy.deepcopy(m2l)
    few = {"m0": refs["m0"], "m1": refs["m1"]}
    with pytest.raises(MotionlangError, match="must not be its describer"):
        ev.evaluate_round_trip(l2m, m2l, few, 0.5, method="sample", width=3, max_frames=8,
                               reranker=m2l)
    with pytest.raises(MotionlangError, match="feature sets"):   # none to compare
        ev.evaluate_round_trip(l2m, m2l, few, 0.5, method="sample", width=3, max_frames=8,
                               reranker=ranker)
    _same_features(l2m, ranker)
    # a ranker that prefers the L2M's least likely sample: that one must be described
    import motionlang.models.seq2seq.decode.rerank as rr
    monkeypatch.setattr(rr, "sentence_log_probs",
                        lambda model, motions, sentence: np.arange(len(motions), dtype=float))
    real_rerank, seen, described = ev.rerank, [], []

    def spy_rerank(hyps, model, sentence):
        assert model is ranker
        seen.append([h for h, _ in hyps])
        return real_rerank(hyps, model, sentence)
    monkeypatch.setattr(ev, "rerank", spy_rerank)
    monkeypatch.setattr(ev, "describe_features",
                        lambda model, x, width: described.append(x) or [("w4 w5", 0.0)])
    res = ev.evaluate_round_trip(l2m, m2l, few, 0.5, method="sample", width=3, max_frames=8,
                                 reranker=ranker)
    assert res["n_sentences"] == 2 and len(seen) == 2 and all(len(c) == 3 for c in seen)
    assert all(d is c[-1] for d, c in zip(described, seen))


def test_generate_ranks_by_the_reranker_and_shows_its_scores(trained, monkeypatch):
    import copy

    import motionlang.models.seq2seq.decode.rerank as rr
    from motionlang.models.seq2seq.decode.search import generate
    m2l, _, refs = trained
    l2m = tiny("l2m", False)
    l2m.vocab = WORDS
    ranker = copy.deepcopy(m2l)
    _same_features(l2m, ranker)
    plain = generate(l2m, refs["m0"][0], width=3, method="sample", max_frames=6, seed=4)
    monkeypatch.setattr(rr, "sentence_log_probs",
                        lambda model, motions, sentence: -np.arange(len(motions), dtype=float)[::-1])
    ranked = generate(l2m, refs["m0"][0], width=3, method="sample", max_frames=6, seed=4,
                      reranker=ranker)
    assert [s for _, s in ranked] == [0.0, -1.0, -2.0]       # the ranker's scores, best first
    np.testing.assert_allclose(ranked[0][0], plain[-1][0])    # its best: the L2M's last
    with pytest.raises(MotionlangError, match="as text"):
        generate(l2m, [1, 4, 2], width=3, method="sample", max_frames=6, reranker=ranker)


def test_reranker_features_must_be_the_l2m_features():
    import types

    from motionlang.models.seq2seq.decode.rerank import check_same_features
    a = types.SimpleNamespace(features=StubFeatures(3))
    check_same_features(a, types.SimpleNamespace(features=StubFeatures(3)))
    other = StubFeatures(3)
    other.names = ["x", "y", "z"]
    with pytest.raises(MotionlangError, match="--rerank r.pt: .*other feature names"):
        check_same_features(a, types.SimpleNamespace(features=other), "--rerank r.pt")
    other = StubFeatures(3)
    other.kind = "angles"
    with pytest.raises(MotionlangError, match="stub vs angles"):
        check_same_features(a, types.SimpleNamespace(features=other))

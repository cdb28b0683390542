"""The text-motion evaluator (Guo et al. 2022's architecture): config checks, shapes, the
public parameter names and shapes, save -> load, training on a tiny dataset where the
text decides the motion, the offline POS tagger, items from a procedural corpus and the
yardstick on its embeddings."""
from __future__ import annotations

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from motionlang.datasets.evaluator_items import build_evaluator_data, fit_normalizer
from motionlang.errors import DatasetError, MotionlangError
from motionlang.evaluation.metrics.t2m import r_precision
from motionlang.evaluation.t2m.yardstick import format_table, guo_metrics, score_t2m
from motionlang.models.evaluator.config import EvaluatorConfig
from motionlang.models.evaluator.model import TextMotionEvaluator, official_config
from motionlang.models.evaluator.text import POS_CATEGORIES, pos_index, tag, text_inputs
from motionlang.models.registry import load_model
from motionlang.recipes.evaluator_train import train_evaluator
from motionlang.training.trainer import TrainConfig

torch.set_num_threads(1)
TINY = dict(motion_dim=8, drop_last=0, text_hidden=24, motion_hidden=24, movement_hidden=24,
            movement_latent=24, embed_dim=16)
VERBS = ["walks", "runs", "jumps", "kicks", "waves", "turns", "squats", "claps"]
MANNERS = ["slowly", "quickly", "forward", "backward"]


def public_shapes(pose: int = 263, word: int = 300, pos: int = 15, text_h: int = 512,
                  motion_h: int = 1024, move_h: int = 512, latent: int = 512, emb: int = 512):
    """Parameter name -> shape of the public modules (``networks/modules.py`` of
    EricGuo5513/text-to-motion: MovementConvEncoder(pose - 4, move_h, latent),
    MotionEncoderBiGRUCo(latent, motion_h, emb), TextEncoderBiGRUCo(word, pos, text_h, emb)),
    written out from their layer definitions."""
    def gru(h):
        return {f"gru.{w}_l0{r}": s for r in ("", "_reverse") for w, s in
                (("weight_ih", (3 * h, h)), ("weight_hh", (3 * h, h)), ("bias_ih", (3 * h,)),
                 ("bias_hh", (3 * h,)))}

    def head(h, out):
        return {"output_net.0.weight": (h, 2 * h), "output_net.0.bias": (h,),
                "output_net.1.weight": (h,), "output_net.1.bias": (h,),
                "output_net.3.weight": (out, h), "output_net.3.bias": (out,)}
    return {
        "movement_encoder": {"main.0.weight": (move_h, pose - 4, 4), "main.0.bias": (move_h,),
                             "main.3.weight": (latent, move_h, 4), "main.3.bias": (latent,),
                             "out_net.weight": (latent, latent), "out_net.bias": (latent,)},
        "motion_encoder": {"input_emb.weight": (motion_h, latent), "input_emb.bias": (motion_h,),
                           "hidden": (2, 1, motion_h), **gru(motion_h), **head(motion_h, emb)},
        "text_encoder": {"pos_emb.weight": (word, pos), "pos_emb.bias": (word,),
                         "input_emb.weight": (text_h, word), "input_emb.bias": (text_h,),
                         "hidden": (2, 1, text_h), **gru(text_h), **head(text_h, emb)}}


def public_dict(seed: int = 0, **sizes) -> dict:
    g = torch.Generator().manual_seed(seed)
    return {k: {n: torch.randn(s, generator=g) * 0.05 for n, s in v.items()}
            for k, v in public_shapes(**sizes).items()} | {"epoch": 7}


def synthetic_items(n_per: int = 2, seed: int = 0) -> list[dict]:
    """32 captions (verb x manner), each with its own motion pattern (sines whose column
    and frequency the verb picks and whose amplitude and phase the manner picks) + noise."""
    rng = np.random.default_rng(seed)
    items = []
    for v, verb in enumerate(VERBS):
        for m, manner in enumerate(MANNERS):
            for k in range(n_per):
                T = int(rng.integers(14, 22))
                t = np.arange(T)[:, None]
                x = 0.1 * rng.normal(size=(T, 8))
                x[:, v] += (1 + m) * np.sin(0.3 * (1 + v % 3) * t[:, 0] + m)
                x[:, (v + 1 + m) % 8] += 1.5
                items.append({"motion": x.astype(np.float32), "caption": f"a person {verb} "
                              f"{manner}", "id": f"{verb}-{manner}-{k}"})
    return items


def test_config_is_checked():
    for bad in ({"embed_dim": 0}, {"dropout": 1.0}, {"loss": "triplet"}, {"drop_last": 8},
                {"unit_length": 2}, {"n_pos": 12}, {"margin": -1.0}):
        with pytest.raises(MotionlangError, match="EvaluatorConfig"):
            EvaluatorConfig(**{**TINY, **bad})
    assert EvaluatorConfig.official("kit").input_dim == 247
    with pytest.raises(MotionlangError, match="unknown official"):
        EvaluatorConfig.official("babel")


def test_shapes_and_losses():
    torch.manual_seed(0)
    items = synthetic_items()[:5]
    items[0] = {**items[0], "motion": items[0]["motion"][:3]}     # under one unit: padded
    for loss in ("hinge", "infonce"):
        model = TextMotionEvaluator(EvaluatorConfig(**TINY, loss=loss))
        batch = model.collate(items)
        assert batch["motion"].shape[0] == 5 and batch["motion"].shape[1] % 4 == 0
        assert (batch["motion_lengths"] % 4 == 0).all() and batch["motion_lengths"][0] == 4
        assert batch["pos"].shape[-1] == 15 and batch["words"].shape[-1] == 50
        out = model.loss(batch)
        assert out["loss"].ndim == 0 and torch.isfinite(out["loss"])
        assert set(out) == ({"loss", "pos", "neg"} if loss == "hinge" else {"loss", "nce"})
    assert model.embed_motions([it["motion"] for it in items]).shape == (5, 16)
    assert model.embed_texts([it["caption"] for it in items]).shape == (5, 16)
    with pytest.raises(MotionlangError, match=r"\(T >= 1, 8\)"):
        model.embed_motions([np.zeros((10, 9))])


def test_hinge_loss_by_hand():
    """Two pairs at distance 0 and 2, negatives at distance 3: pos = (0 + 4) / 2, neg =
    ((10 - 3)^2 * 2) / 2."""
    model = TextMotionEvaluator(EvaluatorConfig(**TINY))
    t = torch.tensor([[0.0, 0.0], [3.0, 0.0]])
    m = torch.tensor([[0.0, 0.0], [3.0, 2.0]])
    model.encode_text = lambda *a: t
    model.encode_motion = lambda *a: m
    out = model.loss({k: None for k in ("words", "pos", "word_lengths", "motion",
                                        "motion_lengths")})
    # shifted pairs: |t0 - m1| = sqrt(13), |t1 - m0| = 3
    assert float(out["pos"]) == pytest.approx(2.0)
    assert float(out["neg"]) == pytest.approx(((10 - 13 ** 0.5) ** 2 + 49) / 2)
    model.eval()                      # every mismatched pair: the same two here
    assert float(model.loss(dict.fromkeys(("words", "pos", "word_lengths", "motion",
                                            "motion_lengths")))["neg"]) == float(out["neg"])
    # the same caption twice: the two are not negatives of each other, in either mode
    same = {**dict.fromkeys(("words", "pos", "word_lengths", "motion", "motion_lengths")),
            "same_caption": torch.ones(2, 2, dtype=torch.bool)}
    for train in (False, True):
        model.train(train)
        assert float(model.loss(same)["neg"]) == 0.0
    # InfoNCE: the other pair of the same caption leaves the softmax; only the own pair is left
    nce = TextMotionEvaluator(EvaluatorConfig(**{**TINY, "loss": "infonce"}))
    nce.encode_text = lambda *a: t
    nce.encode_motion = lambda *a: m
    assert float(nce.loss(same)["nce"]) == pytest.approx(0.0, abs=1e-6)
    assert float(nce.loss({**same, "same_caption": torch.eye(2, dtype=torch.bool)})["nce"]) > 0


def test_collate_marks_pairs_of_the_same_caption():
    model = TextMotionEvaluator(EvaluatorConfig(**TINY), np.zeros(8), np.ones(8))
    rows = np.zeros((8, 8), dtype=np.float32)
    batch = model.collate([{"motion": rows, "caption": c} for c in (
        "A person walks.", "a person walks", "a person runs")])
    assert batch["same_caption"].tolist() == [[True, True, False], [True, True, False],
                                              [False, False, True]]


def test_public_names_and_shapes_load(tmp_path):
    d = public_dict()
    cfg = official_config(d)
    assert cfg == EvaluatorConfig.official("humanml3d")
    mean, std = np.arange(263.0), np.full(263, 2.0)
    np.save(tmp_path / "mean.npy", mean)
    np.save(tmp_path / "std.npy", std)
    model = TextMotionEvaluator.load_official(d, tmp_path / "mean.npy", tmp_path / "std.npy")
    for key, params in d.items():
        if key != "epoch":
            mine = getattr(model, key).state_dict()
            assert set(mine) == set(params)
            assert all(torch.equal(mine[n], p) for n, p in params.items())
    assert model.mean.tolist() == mean.tolist() and model.std.tolist() == std.tolist()
    # the movement encoder is the public forward: two strided convolutions, then a linear
    x = torch.randn(2, 8, 259)
    mv = d["movement_encoder"]
    h = F.leaky_relu(F.conv1d(x.transpose(1, 2), mv["main.0.weight"], mv["main.0.bias"],
                              stride=2, padding=1), 0.2)
    h = F.leaky_relu(F.conv1d(h, mv["main.3.weight"], mv["main.3.bias"], stride=2,
                              padding=1), 0.2)
    want = h.transpose(1, 2) @ mv["out_net.weight"].T + mv["out_net.bias"]
    with torch.no_grad():
        assert torch.allclose(model.movement_encoder(x), want, atol=1e-5)


def test_public_checkpoint_file_and_mismatches(tmp_path):
    small = dict(pose=20, word=50, text_h=8, motion_h=12, move_h=6, latent=10, emb=4)
    torch.save(public_dict(1, **small), tmp_path / "finest.tar")
    model = TextMotionEvaluator.load_official(tmp_path / "finest.tar", np.zeros(20),
                                              np.ones(20))
    assert model.config.motion_dim == 20 and model.config.embed_dim == 4
    assert model.embed_texts(["a person walks"]).shape == (1, 4)
    with pytest.raises(MotionlangError, match="does not fit"):
        TextMotionEvaluator.load_official(public_dict(1, **small), np.zeros(24), np.ones(24),
                                          EvaluatorConfig(**{**TINY, "motion_dim": 24}))
    with pytest.raises(MotionlangError, match="no text_encoder"):
        TextMotionEvaluator.load_official({"movement_encoder": {}, "motion_encoder": {}},
                                          np.zeros(20), np.ones(20))
    with pytest.raises(MotionlangError, match=r"mean/std must be \(20,\)"):
        TextMotionEvaluator.load_official(tmp_path / "finest.tar", np.zeros(263), np.ones(263))


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    torch.manual_seed(0)
    items = synthetic_items(n_per=4)
    model = TextMotionEvaluator(EvaluatorConfig(**TINY))
    with torch.no_grad():
        before = float(model.loss(model.collate(items[:32]))["loss"])
    cfg = TrainConfig(epochs=50, batch_size=64, lr=1e-2, optimizer="adam", grad_clip=0.5, seed=0,
                      out_dir=str(tmp_path_factory.mktemp("ev")), plot=False, progress=False)
    model, history = train_evaluator(model, items, cfg, body=None)
    return model, items, before, history, cfg


def test_training_learns_the_pairing(trained):
    model, items, before, history, _ = trained
    last = np.mean([h["train"]["loss"] for h in history[-3:]])
    assert last < 0.6 * before, (last, before)
    test = synthetic_items(n_per=1, seed=1)                 # new noise, new lengths
    t = model.embed_texts([it["caption"] for it in test])
    m = model.embed_motions([it["motion"] for it in test])
    top3 = r_precision(t, m, top_k=3)[2]
    assert top3 > 0.4, top3                                  # chance: 3 / 32 = 0.09


def test_save_load_bit_identical(trained, tmp_path):
    model, items, *_ = trained
    model.save(tmp_path / "ev.pt")
    back = load_model(tmp_path / "ev.pt", kind="evaluator")
    motions, captions = [it["motion"] for it in items], [it["caption"] for it in items]
    assert np.array_equal(back.embed_motions(motions), model.embed_motions(motions))
    assert np.array_equal(back.embed_texts(captions), model.embed_texts(captions))
    assert np.array_equal(back.mean, model.mean) and np.array_equal(back.std, model.std)
    best = TextMotionEvaluator.load(trained[4].out_dir + "/best.pt")   # a trainer checkpoint
    assert best.config == model.config


def test_yardstick_on_trained_embeddings(trained):
    model, items, *_ = trained
    captions, motions = [it["caption"] for it in items], [it["motion"] for it in items]
    still = [np.zeros_like(m) for m in motions]
    truth = score_t2m(model, captions, motions, motions[::2], repeats=3)
    flat = score_t2m(model, captions, still, motions[::2], repeats=3)
    assert truth["guo"]["R-precision top-3"][0] > flat["guo"]["R-precision top-3"][0]
    assert truth["guo"]["FID"][0] < flat["guo"]["FID"][0]
    assert "b32/t2m/R01" in truth["retrieval"] and "FID" in format_table(truth)
    calls = []
    again = score_t2m(model, captions, lambda i: calls.append(i) or motions, motions[::2],
                      repeats=3)                        # a new generation per repetition
    assert calls == [0, 1, 2] and again["guo"] == truth["guo"]


def test_guo_metrics_by_hand():
    rng = np.random.default_rng(0)
    text = rng.normal(size=(64, 4))
    out = guo_metrics(text, text, text, repeats=4)
    assert out["R-precision top-1"] == pytest.approx((1.0, 0.0))
    assert out["MM-Dist"] == pytest.approx((0.0, 0.0), abs=1e-9)
    assert out["FID"][0] == pytest.approx(0.0, abs=1e-6)
    far = guo_metrics(text, text + 10.0, text, repeats=2)
    assert far["MM-Dist"][0] == pytest.approx(20.0) and far["FID"][0] == pytest.approx(400.0)


def test_tagger_and_text_inputs():
    assert tag("A man walks forward slowly.") == ["a/DET", "man/NOUN", "walk/VERB",
                                                  "forward/ADV", "slowly/ADV"]
    assert tag("He waves his right arm twice") == ["he/PRON", "wave/VERB", "his/PRON",
                                                   "right/ADJ", "arm/NOUN", "twice/NUM"]
    assert tag("someone is running in a circle")[1:3] == ["is/AUX", "run/VERB"]
    assert tag("a man sat down")[2] == "sit/VERB"
    # the public override: a VIP word's class wins over its tag; other tags -> OTHER
    assert POS_CATEGORIES[pos_index("walk", "NOUN")] == "Act_VIP"
    assert POS_CATEGORIES[pos_index("left", "ADJ")] == "Loc_VIP"
    assert POS_CATEGORIES[pos_index("and", "CCONJ")] == "OTHER"
    words, pos = text_inputs(["a/DET", "zqxjv/NOUN"] + ["arm/NOUN"] * 30, _Vectors(), 20)
    assert words.shape == (22, 3) and pos.shape == (22, 15)
    assert pos[[0, -1], POS_CATEGORIES.index("OTHER")].tolist() == [1.0, 1.0]   # sos, eos
    assert pos[2, POS_CATEGORIES.index("OTHER")] == 1.0 and words[2].tolist() == [9, 9, 9]


class _Vectors:
    """Three-number word vectors of a few words; ``unk`` is (9, 9, 9)."""

    dim = 3
    table = {"sos": 1.0, "eos": 2.0, "unk": 9.0, "a": 3.0, "arm": 4.0}

    def __contains__(self, w):
        return w in self.table

    def __getitem__(self, w):
        return np.full(3, self.table[w], dtype=np.float32)


def test_items_from_a_procedural_corpus(tmp_path):
    from motionlang.datasets.synth import write_corpus
    write_corpus(tmp_path / "c", n=4, seed=3, workers=1, show_progress=False)
    data = build_evaluator_data(tmp_path / "c", fractions=(0.5, 0.25, 0.25))
    items = [it for split in data.items.values() for it in split]
    assert data.motion_dim == 251 and items
    assert all(it["motion"].shape[1] == 251 and it["motion"].dtype == np.float32
               for it in items)
    mean, std = fit_normalizer(items, "kit")
    assert mean.shape == std.shape == (251,) and (std > 0).all()
    model = TextMotionEvaluator(EvaluatorConfig(**{**TINY, "motion_dim": 251, "drop_last": 4}),
                                mean, std)
    assert model.loss(model.collate(items))["loss"].isfinite()


def test_tokens_from_the_data_win_unless_untagged():
    from motionlang.models.evaluator.text import caption_tokens
    given = ["a/DET", "person/NOUN", "walk/VERB"]
    assert caption_tokens("whatever", given) == given
    assert caption_tokens("a man walks", ["a/DET", "man/X", "walks/X"]) == tag("a man walks")
    assert caption_tokens("a man walks", None) == tag("a man walks")


def test_items_laid_on_the_training_motions_median_bones(tmp_path):
    """bones="median": the training motions' median bone lengths, every split's rows made
    on them (a row's bones are the joints' distances, back from the rows); the rows of a
    generated motion on a body 1.2 times as big are those of the motion itself."""
    from motionlang.datasets.evaluator_items import body_joints_of
    from motionlang.datasets.synth import write_corpus
    from motionlang.evaluation.t2m.yardstick import positions_rows
    from motionlang.features.h3d_vectors import KIT_H3D, vectors_to_joints
    from motionlang.features.joint_map import bone_lengths21
    write_corpus(tmp_path / "c", n=4, seed=3, workers=1, show_progress=False)
    plain = build_evaluator_data(tmp_path / "c", fractions=(0.5, 0.25, 0.25))
    data = build_evaluator_data(tmp_path / "c", fractions=(0.5, 0.25, 0.25), bones="median")
    assert plain.bones is None and len(data.bones) == 20
    train_ids = dict.fromkeys(it["id"] for it in data.items["train"])
    want = np.median(np.concatenate(
        [bone_lengths21(body_joints_of(data.records[i].load_motion())) for i in train_ids]),
        axis=0)
    assert data.bones == pytest.approx(want)
    for it in data.items["test"][:1]:
        joints = vectors_to_joints(it["motion"], KIT_H3D) * KIT_H3D.unit
        assert np.allclose(bone_lengths21(joints), want, atol=1e-3)
    p = body_joints_of(data.records[next(iter(train_ids))].load_motion())
    assert np.allclose(positions_rows(p * 1.2, data.bones), positions_rows(p, data.bones),
                       atol=1e-3)
    assert not np.allclose(positions_rows(p * 1.2), positions_rows(p), atol=1e-3)
    with pytest.raises(DatasetError, match="median"):
        build_evaluator_data(tmp_path / "c", "smpl", bones="median")
    with pytest.raises(MotionlangError, match="20 lengths"):
        EvaluatorConfig(bones=[0.1] * 3)

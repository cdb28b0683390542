"""``motionlang train crbm`` / ``crbm generate | fill | reproduce`` end to end, tiny models."""
from __future__ import annotations

import json

import numpy as np
import pytest

from helpers.data import shared_file
from motionlang.cli.main import main
from motionlang.evaluation.crbm.fill import load_cmu35
from motionlang.evaluation.crbm.generation import StyleLabeller, generation_report
from motionlang.evaluation.crbm.reproduce import (
    frames_to_motion,
    model_frames,
    model_frames_to_channels,
)
from motionlang.models.crbm.config import CRBMConfig
from motionlang.models.crbm.model import CRBM
from motionlang.models.crbm.stack import CRBMStack


@pytest.fixture(scope="module")
def data_dir():
    return shared_file("cmu35/cmu35WalkJog.mat").parent


@pytest.fixture(scope="module")
def model_path(data_dir, tmp_path_factory):
    run = tmp_path_factory.mktemp("crbm") / "run"
    assert main(["train", "crbm", "--data", str(data_dir), "--out", str(run), "--epochs", "3",
                 "--hidden", "12", "--quiet", "--level2",
                 "--level2-hidden", "5", "--level2-order", "2"]) == 0
    assert json.loads((run / "commands.jsonl").read_text())["n_hidden"] == 12
    return run / "model.npz"


def test_train_writes_a_reloadable_checkpoint(model_path):
    m = CRBM.load(model_path)
    assert m.config.n_hidden == 12 and len(m.history) == 3 and m.n_visible == 59
    # the selected noise on the past frames is the default, kept in the checkpoint; the
    # second level (hidden probabilities, not normalised units) trains without it
    from motionlang.evaluation.crbm.reproduce import SELECTED
    assert m.config.history_noise == SELECTED["history_noise"] > 0
    stack = CRBMStack.load(model_path.with_name("stack.npz"))
    assert stack.level2.config.history_noise == 0.0


def test_generate_and_fill_outputs(model_path, data_dir, tmp_path, capsys):
    out = tmp_path / "gen.npy"
    assert main(["crbm", "generate", str(model_path), str(out), "--data", str(data_dir),
                 "--frames", "20", "--gibbs", "2", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert np.load(out).shape == (23, 59)
    assert report["fraction_walk"] + report["fraction_jog"] == pytest.approx(1.0)
    two = model_path.with_name("stack.npz")
    assert main(["crbm", "generate", str(two), str(out), "--data", str(data_dir), "--start", "jog",
                 "--frames", "10", "--gibbs", "2", "--json"]) == 0
    json.loads(capsys.readouterr().out)
    assert np.load(out).shape == (15, 59)   # 3 + 2 real frames start a two-level model
    assert report["fraction_walk"] + report["fraction_jog"] == pytest.approx(1.0)
    png = tmp_path / "fill.png"
    # a run folder stands for its model.npz
    assert main(["crbm", "fill", str(model_path.parent), str(png), "--data", str(data_dir),
                 "--part", "upper-body", "--repeats", "2", "--gibbs", "2", "--json"]) == 0
    errs = json.loads(capsys.readouterr().out)
    assert png.stat().st_size > 1000
    assert errs["nearest neighbour"] == pytest.approx(22.20, rel=0.01)
    bvh = tmp_path / "fill.bvh"
    assert main(["crbm", "fill", str(model_path), str(bvh), "--data", str(data_dir),
                 "--repeats", "1", "--gibbs", "1"]) == 0
    assert bvh.read_text().startswith("HIERARCHY")


def test_reproduce_json_with_a_saved_model(model_path, data_dir, capsys):
    assert main(["crbm", "reproduce", "--data", str(data_dir), "--model", str(model_path),
                 "--repeats", "2", "--gibbs", "2", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert set(result["table"]) == {"35_29", "35_18"}
    assert result["table"]["35_29"]["upper body"]["nearest neighbour"] == pytest.approx(22.20, rel=0.01)


def test_errors_are_one_line(data_dir, tmp_path, capsys):
    assert main(["crbm", "generate", str(tmp_path / "none.npz"), str(tmp_path / "o.npy"),
                 "--data", str(data_dir)]) == 2
    assert "no such model file" in capsys.readouterr().err
    assert main(["train", "crbm", "--data", str(tmp_path), "--out", str(tmp_path / "run"),
                 "--quiet"]) == 2


def test_ml_train_runs_the_recipe(data_dir, tmp_path):
    import motionlang as ml
    from motionlang.models.crbm.config import SELECTED
    out = tmp_path / "run"
    path = ml.train("crbm", str(data_dir), out, n_hidden=6, epochs=2, lr=2e-3, quiet=True,
                    level2=True, level2_hidden=4, level2_order=2)
    assert path == out / "model.npz"
    m = ml.load_model(path)
    # the recipe's defaults (the selected settings) under the given fields; --lr's rule
    assert (m.config.n_hidden, m.config.epochs, m.config.lr_autoregressive) == (6, 2, 2e-3)
    assert m.config.weight_decay_autoregressive == SELECTED["weight_decay_autoregressive"]
    assert CRBMStack.load(out / "stack.npz").level2.config.order == 2
    assert json.loads((out / "commands.jsonl").read_text())["level2_hidden"] == 4
    from motionlang.errors import MotionlangError
    with pytest.raises(MotionlangError, match="unknown option 'grad_clip'"):
        ml.train("crbm", str(data_dir), tmp_path / "x", grad_clip=1.0)   # no shared trainer
    with pytest.raises(MotionlangError, match="cannot be resumed"):
        ml.train("crbm", str(data_dir), out, resume=True)
    with pytest.raises(MotionlangError, match="level2_order must be <= 1000"):
        ml.train("crbm", str(data_dir), tmp_path / "x", level2_order=5000)
    assert not (tmp_path / "x").exists()


def test_crbm_options_are_checked_by_the_config(data_dir, tmp_path, capsys):
    train = ["train", "crbm", "--data", str(data_dir), "--out", str(tmp_path / "run")]
    reproduce = ["crbm", "reproduce", "--data", str(data_dir), "--quiet"]
    for argv, fragment in (
            (train + ["--level2-hidden", "0"], "--level2-hidden must be an integer in 1..4096"),
            (train + ["--hidden", "5000"], "--hidden must be an integer in 1..4096"),
            (train + ["--momentum", "1.5"], "--momentum must be a number in [0, 1)"),
            (reproduce + ["--ar-weight-decay", "-1"], "--ar-weight-decay must be"),
            (reproduce + ["--seed", "-1"], "--seed must be an integer in 0..")):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert fragment in err, err
    assert not (tmp_path / "run").exists()


def test_model_frames_invert_to_channels_and_a_motion(data_dir):
    data = load_cmu35(data_dir)
    c = data.test["35_29"]
    back = model_frames_to_channels(model_frames(c), c, tuple(c[0, [0, 2]]))
    np.testing.assert_allclose(back, c, atol=1e-9)
    motion = frames_to_motion(model_frames(c), data, data_dir / "35.asf")
    assert motion.n_frames == len(c) and motion.fps == 30.0
    pos = motion.positions()
    assert np.isfinite(pos).all() and pos[..., 1].min() > -0.2   # feet near the floor, not below


def test_two_level_model_and_generation_report(data_dir):
    data = load_cmu35(data_dir)
    seqs = [model_frames(c) for c in data.train]
    l1 = CRBM(CRBMConfig(n_hidden=8, epochs=2), 59).fit(seqs)
    stack = CRBMStack.fit(l1, seqs, CRBMConfig(n_hidden=6, epochs=2))
    assert stack.level2.config.visible == "binary" and stack.n_init == 6
    gen = stack.generate(seqs[0][:6], 15, n_gibbs=2)
    assert gen.shape == (21, 59) and np.isfinite(gen).all()
    np.testing.assert_array_equal(gen[:6], seqs[0][:6])
    rep = generation_report(l1, data, n_frames=10, n_gibbs=2)
    assert set(rep) == {"walk", "jog"} and 0 <= rep["walk"]["style_kept"] <= 1
    # forward speed next to the training trials' own (walks ~1.2 m/s, jogs ~3.4 m/s)
    assert 1.1 < rep["walk"]["forward_speed_training"] < 1.35
    assert 3.0 < rep["jog"]["forward_speed_training"] < 3.7
    assert np.isfinite(rep["walk"]["forward_speed_last_half"])
    # the labeller gives a training frame its own trial's label
    lab = StyleLabeller(data, l1.mean, l1.std)
    jog_trial = data.train[data.train_names.index("35_20")]
    assert (lab(model_frames(jog_trial)) == "jog").all()

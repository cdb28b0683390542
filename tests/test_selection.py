"""Choosing a text-to-motion model's epoch on validation R-precision
(``evaluation.t2m.selection``): a tiny evaluator and a tiny two-stream model on a tiny
procedural corpus; the two-stream recipe's options for it refused as one line."""
from __future__ import annotations

import math

import pytest
import torch

from helpers.evaluator import tiny_corpus, tiny_evaluator
from helpers.twostream import HashTokens
from motionlang.cli.main import main
from motionlang.evaluation.t2m.selection import (
    DIVERSITY,
    FID,
    TOP3,
    format_scores,
    guo_selector,
)
from motionlang.training.run_files import read_training_checkpoint
from motionlang.training.trainer import TrainConfig

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return tiny_corpus(tmp_path_factory.mktemp("corpus"))


@pytest.fixture(scope="module")
def evaluator(corpus, tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("MOTIONLANG_CACHE", str(tmp_path_factory.mktemp("cache")))
    yield tiny_evaluator(corpus, tmp_path_factory.mktemp("runs") / "evaluator")
    mp.undo()


def test_the_scores_line():
    assert format_scores({TOP3: 0.7, FID: 9.0, DIVERSITY: 1.0}) == \
        "top-3 0.700, FID 9.0, diversity 1.0"
    assert format_scores({"loss": 1.0}) == ""


def test_the_run_keeps_the_epoch_of_the_best_validation_r_precision(corpus, evaluator,
                                                                    tmp_path):
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.models.twostream.model import TwoStreamModel
    from motionlang.recipes.twostream_train import make_config, train_twostream
    data = build_twostream_data(corpus, max_frames=12, cache_dir=tmp_path / "cache")
    select = guo_selector(evaluator, str(corpus), batch_size=4, repeats=2)
    torch.manual_seed(0)
    model = TwoStreamModel(make_config(h1=4, h2=8, h=16, disc_hidden=8),
                           data.features.normalizer, text_encoder=HashTokens()).eval()
    first = select(model)
    assert first == select(model)                      # the same motions, the same scores
    assert first["select"] == -first[TOP3] and 0.0 <= first[TOP3] <= 1.0
    assert math.isfinite(first[FID]) and first[FID] >= 0.0 and first[DIVERSITY] > 0.0
    cfg = TrainConfig(epochs=3, batch_size=8, lr=3e-3, seed=0, out_dir=str(tmp_path / "run"),
                      plot=False, progress=False)
    model, hist = train_twostream(model, data.items["train"], cfg,
                                  val_items=data.items["val"], select=select)
    assert all(TOP3 in h["val"] and FID in h["val"] for h in hist)
    chosen = [h for h in hist if h.get("selected")]
    assert len(chosen) == 1 and chosen[0]["val"][TOP3] == max(h["val"][TOP3] for h in hist)
    assert chosen[0]["epoch"] == min(h["epoch"] for h in hist      # the first of equals
                                     if h["val"][TOP3] == chosen[0]["val"][TOP3])
    best = read_training_checkpoint(tmp_path / "run" / "best.pt")
    assert best["epoch"] == chosen[0]["epoch"] and best["best_by"] == select.key
    assert f"of {len(data.splits['val'])} val pairs of {corpus}" in select.key
    for k, v in model.state_dict().items():            # the model returned is that epoch's
        assert torch.equal(v, best["model"]["state_dict"][k]), k
    # resumed with another selector and nothing left to train: no epoch was scored by it,
    # so the final weights stay (best.pt was ranked by the first)
    other = guo_selector(evaluator, str(corpus), batch_size=4, repeats=2, seed=1)
    final = read_training_checkpoint(tmp_path / "run" / "last.pt")["model"]["state_dict"]
    again, hist2 = train_twostream(model, data.items["train"], cfg,
                                   val_items=data.items["val"], select=other, resume=True)
    assert not any(h.get("selected") for h in hist2)
    for k, v in again.state_dict().items():
        assert torch.equal(v, final[k]), k


@pytest.mark.parametrize("extra, message", [
    (["--select-data", "x"], "--select-data needs --select-evaluator"),
    (["--select-pairs", "-1"], "--select-pairs"),
])
def test_bad_selection_options_are_one_line(extra, message, corpus, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", "twostream", "--data", str(corpus), "--out", str(out),
                 *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and not out.exists()


def test_several_sources_need_the_selection_source(corpus, evaluator, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", "twostream", "--data", f"{corpus}@1", "--data", f"{corpus}@1", "--out",
                 str(out), "--select-evaluator", str(evaluator)]) == 2
    assert "needs --select-data" in capsys.readouterr().err and not out.exists()


def test_the_two_stream_recipe_scores_each_epoch_with_its_first_pose_fitted():
    from motionlang.recipes.twostream import WithHeads
    calls = []

    def select(model):
        calls.append(("select", model))
        return {"select": -0.5}

    select.key = "top-3 of 256 val pairs"   # type: ignore[attr-defined]
    scored = WithHeads(select, lambda model: calls.append(("fit", model)))
    assert scored("m") == {"select": -0.5} and calls == [("fit", "m"), ("select", "m")]
    # a resumed run does not rank its epochs against the bare selector's scores
    assert scored.key != select.key and scored.key.startswith(select.key)

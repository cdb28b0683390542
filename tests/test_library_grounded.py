"""The analysis in the index (``library.grounded``): a take that shows what a query asks for is
found even where the learned model is blind to the words, the hit says why, and the filters
(``--where``, ``--min-duration``, ``--rig``, ``--path-glob``) decide what may be a hit.

The library is made here (``helpers.grounded``): a body that sits down on a seat, one that
stands, and a walk. The learned side is a hand-made encoder that knows only "walks" and
"stands": "sits" is half a walk to it.
"""
from __future__ import annotations

import importlib.util
import json
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import motionlang as ml
from helpers.grounded import hand_made, make_library
from motionlang.cli.main import main
from motionlang.errors import MotionlangError
from motionlang.library import index as index_module
from motionlang.library.embedder import Embedder
from motionlang.library.grounded import matches, valid_findings, where_actions
from motionlang.library.options import SearchOptions, seconds
from motionlang.library.search import Library
from motionlang.library.store import load_index, save_index


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return make_library(tmp_path_factory.mktemp("grounded"))


def test_the_index_holds_what_the_analysis_saw(library):
    _, out = library
    found = {e.path: {f["label"] for f in e.findings} for e in load_index(out).entries}
    assert "sit" in found["chairs/sit.bvh"]
    assert "sit" not in found["stand.bvh"] | found["walk.bvh"]
    assert "walk" in found["walk.bvh"]


def test_a_sitting_take_is_found_where_the_model_is_blind(library):
    _, out = library
    lib = Library.open(out, hand_made())
    hits = lib.search("someone sits", k=3)
    assert hits[0].file == "chairs/sit.bvh" and hits[0].why.startswith("sits: ")
    assert 0.8 <= hits[0].start <= 2.0 and 3.8 <= hits[0].end <= 5.5   # the sitting span
    assert all(not h.why for h in hits[1:])   # the others only resemble the words
    # the learned model alone ranks the walk first: "sits" is half walk to it
    assert lib.search("someone sits", k=3, grounded=False)[0].file == "walk.bvh"


def test_filters_decide_which_takes_may_be_hits(library):
    _, out = library
    lib = Library.open(out, hand_made())
    with pytest.warns(UserWarning, match="no take among those the filters allow that stands"):
        only = lib.search("someone stands", k=5, where="sit")   # standing is not sitting
    assert {h.file for h in only} == {"chairs/sit.bvh"}
    assert lib.search("someone walks", where="sitting", min_duration="10s") == []
    with pytest.warns(UserWarning, match="that walks; the hits without a reason are"):
        chairs = lib.search("someone walks", k=5, path_glob="chairs/*")
    assert {h.file for h in chairs} == {"chairs/sit.bvh"}
    rig = load_index(out).entries[0].rig["map"]
    assert len(lib.search("someone walks", k=5, rig=rig)) == 3
    assert lib.search("someone walks", k=5, rig="no-such-rig") == []
    with pytest.raises(MotionlangError, match="--where 'happily' names no action"):
        lib.search("someone walks", where="happily")


def test_matching_findings_by_hand():
    f = [{"label": "walk", "start": 0.0, "end": 4.0, "confidence": 0.9, "side": None,
          "count": 1},
         {"label": "sit", "start": 5.0, "end": 9.0, "confidence": 0.8, "side": None,
          "count": 1},
         {"label": "jump", "start": 20.0, "end": 20.4, "confidence": 0.7, "side": None,
          "count": 1}]
    assert valid_findings(f) and not valid_findings([{**f[0], "end": -1.0}])
    assert not valid_findings([{**f[0], "label": "fly"}]) and not valid_findings("x")
    assert not valid_findings([{**f[0], "label": ["walk"]}])   # unhashable: no TypeError
    both = matches(f, ["walk", "sit"], 30.0)   # 1 s apart: one hit showing both
    assert len(both) == 1 and both[0].actions == ("walk", "sit")
    assert (both[0].start, both[0].end) == (0.0, 9.5)
    assert both[0].why == "walks: 0.0-4.0 s; sits: 5.0-9.0 s"
    assert matches(f, ["climb"], 30.0) == []          # a jump is no climb
    assert matches(f, ["jump"], 30.0, min_duration=1.0) == []
    assert where_actions("hopping") == ["jump"]


def test_a_dance_answers_for_its_moves_after_a_take_that_shows_them_alone():
    dance = {"label": "dance", "start": 3.0, "end": 9.3, "confidence": 0.9, "side": None,
             "count": 1, "moves": ["kick", "raise", "spin"]}
    kick = {"label": "kick", "start": 1.0, "end": 1.4, "confidence": 0.9, "side": "left",
            "count": 2}
    assert valid_findings([dance]) and not valid_findings([{**dance, "moves": ["fly"]}])
    assert not valid_findings([{**dance, "moves": [["kick"]]}])
    inside = matches([dance], ["kick"], 10.0)
    assert len(inside) == 1 and inside[0].why == "dances (kicks among its moves): 3.0-9.3 s"
    assert inside[0].shows == (3.0, 9.3)
    alone = matches([kick], ["kick"], 10.0)
    assert alone[0].why == "kicks: 1.0-1.4 s" and alone[0].confidence > inside[0].confidence
    # search ranks a take's own kick first even where the dance's confidence ties it
    assert alone[0].direct == 1 and inside[0].direct == 0
    assert matches([dance], ["dance"], 10.0)[0].why == "dances: 3.0-9.3 s"
    assert matches([dance], ["punch"], 10.0) == []   # not among its moves
    assert matches([{**dance, "moves": []}], ["kick"], 10.0) == []


def test_durations_and_options():
    assert seconds("2s", "x") == 2.0 and seconds("500ms", "x") == 0.5
    assert seconds(3, "x") == 3.0 and seconds("1.5min", "x") == 90.0
    for bad in ("two", "-1", "inf", True):
        with pytest.raises(MotionlangError, match="x must be"):
            seconds(bad, "x")
    with pytest.raises(MotionlangError, match="SearchOptions.k"):
        SearchOptions(k=0)
    assert SearchOptions(min_duration="2s").min_duration == 2.0


def test_an_index_without_findings_is_searched_and_brought_up_to_date(library, tmp_path,
                                                                     monkeypatch):
    _, out = library
    old = tmp_path / "old.idx"
    data = load_index(out)
    for e in data.entries:
        e.findings = None
    save_index(data, old)
    meta = json.loads(str(np.load(old)["meta"]))
    assert all(e["findings"] is None for e in meta["entries"])
    lib = Library.open(old, hand_made())
    with pytest.warns(UserWarning, match="made before indexes held the analysis"):
        hits = lib.search("someone sits", k=1)
    assert not hits[0].why
    with pytest.raises(MotionlangError, match="old.idx: made before.*--where"):
        lib.search("someone walks", where="sit")
    emb = hand_made()
    s = ml.index(library[0], old, emb, show_progress=False)
    assert (s.embedded, s.reused, s.analysed, emb.embedded) == (0, 3, 3, 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert Library.open(old, hand_made()).search("someone sits", k=1)[0].why
    # findings of older detectors are made anew too, the vectors kept
    monkeypatch.setattr(index_module, "ANALYSIS", index_module.ANALYSIS + 1)
    again = ml.index(library[0], old, emb, show_progress=False)
    assert (again.analysed, again.embedded, load_index(old).analysis) == (
        3, 0, index_module.ANALYSIS)
    # a take an older index read at another rate than the rate check now gives (its
    # header's, where its body now says otherwise) is embedded anew: its timeline moved
    data = load_index(old)
    data.analysis = index_module.ANALYSIS - 1
    data.entries[0].fps = 25.0
    save_index(data, old)
    again = ml.index(library[0], old, emb, show_progress=False)
    assert (again.embedded, again.reused, again.analysed) == (1, 2, 2)
    assert [e.fps for e in load_index(old).entries] == [e.fps for e in load_index(out).entries]


def test_the_cli_prints_why_and_takes_the_filters(library, capsys, monkeypatch):
    _, out = library
    monkeypatch.setattr(Embedder, "load", classmethod(lambda cls, model=None: hand_made()))
    assert main(["search", "someone sits", "--index", str(out), "-k", "2"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert "chairs/sit.bvh" in first and "(sits: " in first
    with pytest.warns(UserWarning, match="sees no take"):
        assert main(["search", "someone walks", "--index", str(out), "--where", "sit",
                     "--min-duration", "1s", "--json"]) == 0
    assert [h["file"] for h in json.loads(capsys.readouterr().out)] == ["chairs/sit.bvh"]
    assert main(["search", "someone walks", "--index", str(out), "--min-duration",
                 "soon"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--min-duration must be a duration" in err
    # filters that leave nothing: said, with the rigs the index does hold
    assert main(["search", "someone walks", "--index", str(out), "--rig", "flibber"]) == 0
    said = capsys.readouterr().out.strip()
    assert said.startswith(f"no take of {out} matches --rig flibber (the rigs of its takes: ")
    assert main(["search", "someone walks", "--index", str(out), "--rig", "flibber",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == []


def test_workers_give_the_index_one_process_gives(library, tmp_path):
    root, out = library
    two = tmp_path / "two.idx"
    s = ml.index(root, two, hand_made(), workers=2, show_progress=False)
    assert s.embedded == 3
    a, b = load_index(out), load_index(two)
    assert a.entries == b.entries and a.failed == b.failed
    np.testing.assert_allclose(a.vectors, b.vectors, rtol=1e-6)
    np.testing.assert_array_equal(a.spans, b.spans)
    blind = Embedder("x", "y", lambda s: np.zeros(2), lambda m: np.zeros(2))
    with pytest.raises(MotionlangError, match="--workers needs a model given by name"):
        ml.index(root, tmp_path / "three.idx", blind, workers=2, show_progress=False)


@pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="ray not installed")
def test_ray_with_two_workers_gives_the_index_one_process_gives(library, tmp_path,
                                                               monkeypatch):
    root, out = library
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    # Ray's workers import the hand-made encoder's functions from the tests' helpers
    here = str(Path(__file__).resolve().parent)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        p for p in (here, os.environ.get("PYTHONPATH", "")) if p))
    on_ray = tmp_path / "ray.idx"
    ray_tmp = Path(os.environ.get("RAY_TMPDIR", "/tmp")) / "ray"   # Ray's own choice
    sessions = set(ray_tmp.glob("session_*"))
    s = ml.index(root, on_ray, hand_made(), workers=2, engine="ray", show_progress=False)
    assert s.embedded == 3
    # the Ray started for the run leaves no session folder behind
    assert set(ray_tmp.glob("session_*")) == sessions
    a, b = load_index(out), load_index(on_ray)
    assert a.entries == b.entries and a.failed == b.failed
    np.testing.assert_allclose(a.vectors, b.vectors, rtol=1e-6)
    again = ml.index(root, on_ray, hand_made(), workers=2, engine="ray", show_progress=False)
    assert (again.embedded, again.reused) == (0, 3)   # nothing sent to Ray at all


def test_a_worker_that_dies_is_one_line_and_the_index_keeps_what_was_done(library,
                                                                         tmp_path):
    from helpers.grounded import dying
    root, _ = library
    out = tmp_path / "dies.idx"
    with pytest.raises(MotionlangError, match="worker process died.*run the same command"):
        ml.index(root, out, dying(), workers=2, show_progress=False)
    # what came back before the pool broke, in order (a result still in the pipe when the
    # worker died is lost with it; with nothing embedded no index is written)
    kept = [e.path for e in load_index(out).entries] if out.exists() else []
    assert kept in ([], ["chairs/sit.bvh"], ["chairs/sit.bvh", "stand.bvh"])
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["dies.idx"])   # no temp files
    s = ml.index(root, out, hand_made(), show_progress=False)
    assert (s.reused, s.embedded) == (len(kept), 3 - len(kept))

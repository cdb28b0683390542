"""A frame rate that looks wrong (``analysis/rate.py``): a walk or a jump whose header
declares a video-like rate for frames captured at 120 Hz is named, with the rate its steps
fit or its flight falls at g, and read at that rate; a walk or a jump at its true rate, a
body standing still or held up off the floor, and a high declared rate are not."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from helpers.bodies import FPS, I, hold, pose
from helpers.data import shared_file
from helpers.grounded import walking
from motionlang.analysis.rate import at_its_rate, fall_rate, rate_hint
from motionlang.cli.main import main
from motionlang.features.body21 import centre_of_mass21
from motionlang.features.joint_map import positions21
from motionlang.formats import read_motion, write_motion
from motionlang.library.scan import read_takes
from motionlang.rendering.output import body_motion


def _four_times_as_many(p: np.ndarray) -> np.ndarray:
    """The same motion sampled four times as often (linear in between)."""
    t = np.arange(len(p))
    fine = np.arange(0, len(p) - 1 + 1e-9, 0.25)
    flat = p.reshape(len(p), -1)
    return np.stack([np.interp(fine, t, flat[:, j]) for j in range(flat.shape[1])],
                    axis=1).reshape(len(fine), 21, 3)


def test_a_walk_captured_at_120_hz_but_declared_at_30_is_named():
    walk = walking(8.0)                       # 30 Hz frames: 1.8 steps a second
    assert rate_hint(walk, FPS) is None       # at its own rate: as people walk
    dense = _four_times_as_many(walk)         # the same walk in 120 Hz frames
    hint = rate_hint(dense, FPS)              # ... declared at 30 Hz
    assert hint is not None and 120.0 in hint.rates and 60.0 not in hint.rates
    at = dict(zip(hint.rates, hint.cadences))
    assert at[120.0] == pytest.approx(4 * hint.declared_cadence, rel=0.05)
    assert 1.4 <= at[120.0] <= 2.4
    assert "pass --source-fps" in hint.line("walk.bvh") and "at 120 Hz" in hint.line("w")
    assert rate_hint(dense, 4 * FPS) is None   # declared right: nothing to say


def test_standing_still_and_high_rates_say_nothing():
    assert rate_hint(hold(pose(), 10.0), FPS) is None
    assert rate_hint(_four_times_as_many(walking(8.0)), 60.0) is None   # above 30 Hz


def test_the_cmu_walk_as_makehuman_declares_it(shared_data, tmp_path):
    amc = read_motion(shared_file("cmu35/35_01.amc"), skeleton=shared_file("cmu35/35.asf"))
    slow = amc.replace(fps=25.0)   # MakeHuman's header for CMU's 120 Hz takes
    with pytest.warns(UserWarning, match="header says 25 Hz.*at 120 Hz 2.3.*"
                                         "--source-fps"):
        read = at_its_rate(slow, "35_01.bvh")
    assert read.fps in (100.0, 120.0) and read.meta["declared_fps"] == 25.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert at_its_rate(amc, "35_01.amc") is amc   # its own 120 Hz: no warning
    assert positions21(amc).shape[1] == 21
    path = tmp_path / "slow.bvh"
    write_motion(slow, path)
    with pytest.warns(UserWarning, match="at 120 Hz.*read at 1[02]0 Hz.*--source-fps"):
        assert main(["info", str(path)]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["info", str(path), "--source-fps", "120"]) == 0


def _jumps(fps: float, g: float = 9.81) -> np.ndarray:
    """(T, 21, 3) a body standing, jumping up twice (0.45 s flights falling at ``g``) and
    standing, in ``fps`` Hz frames."""
    n = int(round(4.0 * fps))
    p = np.repeat(pose()[None], n, axis=0)
    t = np.arange(n) / fps
    for start in (1.0, 2.5):
        up = (t > start) & (t < start + 0.45)
        p[up, :, 1] += (g / 2 * (t[up] - start) * (start + 0.45 - t[up]))[:, None]
    return p


def test_a_jump_captured_at_120_hz_but_declared_at_25_falls_as_at_120():
    jumps = _jumps(120.0)
    assert rate_hint(jumps, 120.0) is None              # declared above 30 Hz: not checked
    hint = rate_hint(jumps, 25.0)
    assert hint is not None and hint.rate == 120.0 and not hint.cadences
    assert hint.fall_rate == pytest.approx(120.0, rel=0.1) and hint.flights == 2
    assert "fall at 0.04 of gravity" in hint.line("jump.bvh")
    rate, flights, seconds = fall_rate(jumps, 120.0)   # at its own rate, as it is
    assert rate == pytest.approx(120.0, rel=0.1) and 0.5 < seconds < 0.9   # above the floor
    assert rate_hint(_jumps(30.0), 30.0) is None        # a jump at its true 30 Hz


def test_a_body_held_up_or_on_its_hands_is_no_flight_to_time():
    held = np.repeat(pose()[None], 480, axis=0)
    held[120:300, :, 1] += 0.3                          # lifted off the floor and held
    assert rate_hint(held, 25.0) is None
    hands = _jumps(120.0)
    hands[:, [I["LW"], I["RW"]], 1] = 0.02              # a jump with the hands on the floor
    assert rate_hint(hands, 25.0) is None


def test_a_file_is_read_at_the_rate_its_body_says_and_the_user_can_say_otherwise(tmp_path):
    motion, _ = body_motion(_jumps(120.0), 120.0)
    path = tmp_path / "jump.bvh"
    write_motion(motion.replace(fps=25.0), path)
    with pytest.warns(UserWarning, match="jump.bvh: its header says 25 Hz.*read at 120 Hz"):
        assert main(["info", str(path)]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["info", str(path), "--source-fps", "25"]) == 0
    assert read_takes(path)[0].fps == 120.0            # the index reads it so too


def test_the_centre_of_mass_of_a_standing_body_and_of_one_that_lifts_a_leg():
    stand = pose()[None]
    com = centre_of_mass21(stand)[0]
    # a little above half a standing adult's height (this body's hips are at 0.54 of its
    # 1.7 m: 0.60 here), between the feet
    assert 0.52 * 1.7 < com[1] < 0.62 * 1.7 and abs(com[0]) < 1e-9
    lifted = pose(LK=(0.09, 0.7, 0.3), LA=(0.09, 0.35, 0.25), LMrot=(0.09, 0.3, 0.2),
                  LF=(0.09, 0.28, 0.37))[None]
    moved = centre_of_mass21(lifted)[0] - com
    # one leg is 0.161 of the body's mass: raising it lifts the centre by a fraction of its
    # own rise, and toward its side and front
    assert 0.0 < moved[1] < 0.161 * 0.35 and moved[0] == 0.0 and moved[2] > 0.0
    shifted = centre_of_mass21(stand + np.array([1.0, 2.0, 3.0]))[0]
    assert np.allclose(shifted - com, [1.0, 2.0, 3.0])


def test_a_walk_over_a_bridge_and_a_lift_on_a_bar_are_no_flights():
    walk = walking(8.0).copy()                  # 30 Hz, as people walk
    t = np.arange(len(walk)) / FPS
    arc = (t > 2.0) & (t < 5.0)
    walk[arc, :, 1] += (0.4 * np.sin(np.pi * (t[arc] - 2.0) / 3.0))[:, None]
    assert rate_hint(walk, FPS) is None         # it steps as people do: its rate is right
    lift = _jumps(120.0)
    up = lift[:, I["root"], 1] > lift[0, I["root"], 1] + 1e-6
    # the hands held still on a bar above the head while the body rises and falls
    lift[np.ix_(up, [I["LW"], I["RW"]])] = lift[0, [I["LW"], I["RW"]]] + [0.0, 1.2, 0.0]
    assert rate_hint(lift, 25.0) is None


def test_the_index_says_which_takes_it_read_at_their_bodys_rate(tmp_path):
    import motionlang as ml
    from motionlang.library.store import load_index
    from test_library_index import fake
    folder = tmp_path / "lib"
    folder.mkdir()
    motion, _ = body_motion(_jumps(120.0), 120.0)
    write_motion(motion.replace(fps=25.0), folder / "jump.bvh")
    write_motion(motion, folder / "right.bvh")                # its header is right
    s = ml.index(folder, tmp_path / "lib.idx", fake(), show_progress=False)
    assert s.retimed == [("jump.bvh", 25.0, 120.0)]
    assert "1 read at the rate their bodies (or their export's) say, not their header's" \
        in s.text() and "jump.bvh (25 -> 120 Hz)" in s.text()
    assert s.as_dict()["retimed"] == [{"take": "jump.bvh", "declared_fps": 25.0,
                                       "fps": 120.0}]
    entries = {e.path: e for e in load_index(tmp_path / "lib.idx").entries}
    assert (entries["jump.bvh"].fps, entries["jump.bvh"].declared_fps) == (120.0, 25.0)
    assert (entries["right.bvh"].fps, entries["right.bvh"].declared_fps) == (120.0, None)
    again = ml.index(folder, tmp_path / "lib.idx", fake(), show_progress=False)
    assert again.reused == 2 and again.retimed == []         # said when it was embedded

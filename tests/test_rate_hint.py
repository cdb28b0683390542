"""A frame rate that looks wrong (``analysis/rate.py``): a walk whose header declares a
video-like rate for frames captured at 120 Hz is named, with the rate its steps fit; a
walk at its true rate, a body standing still and a high declared rate are not."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from helpers.bodies import FPS, hold, pose
from helpers.data import shared_file
from helpers.grounded import walking
from motionlang.analysis.rate import rate_hint, warn_if_rate_looks_wrong
from motionlang.cli.main import main
from motionlang.features.joint_map import positions21
from motionlang.formats import read_motion, write_motion


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
    with pytest.warns(UserWarning, match="header says 25 Hz.*at 120 Hz 2.3.*pass "
                                         "--source-fps"):
        warn_if_rate_looks_wrong(slow, "35_01.bvh")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_if_rate_looks_wrong(amc, "35_01.amc")   # its own 120 Hz: no warning
    assert positions21(amc).shape[1] == 21
    path = tmp_path / "slow.bvh"
    write_motion(slow, path)
    with pytest.warns(UserWarning, match="at 120 Hz.*--source-fps"):
        assert main(["info", str(path)]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["info", str(path), "--source-fps", "120"]) == 0

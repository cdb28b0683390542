"""Overlapping windows over a take (library/windows.py)."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.library.windows import Window, motion_windows, windows


def test_windows_cover_the_take_with_the_hop_and_end_at_its_end():
    ws = windows(10.0, length=3.0, hop=1.0)
    assert ws[0] == Window(0.0, 3.0) and ws[-1] == Window(7.0, 10.0) and len(ws) == 8
    assert all(b.start - a.start == pytest.approx(1.0) for a, b in zip(ws, ws[1:]))
    tail = windows(10.5, length=3.0, hop=2.0)   # 0, 2, 4, 6 and one for the last 3 s
    assert [w.start for w in tail] == [0.0, 2.0, 4.0, 6.0, 7.5] and tail[-1].end == 10.5


def test_a_short_take_is_one_window_and_bad_sizes_are_refused():
    assert windows(1.2, length=3.0) == [Window(0.0, 1.2)]
    for bad in ({"length": 0.0}, {"hop": -1.0}, {"length": float("nan")}):
        with pytest.raises(MotionlangError, match="window"):
            windows(5.0, **bad)
    assert Window(0, 3).overlaps(Window(2, 5)) and not Window(0, 3).overlaps(Window(3, 6))


def test_motion_windows_cut_the_frames_of_each_span():
    from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS
    from motionlang.kinematics.from_positions import motion_from_positions
    rng = np.random.default_rng(0)
    p = np.cumsum(rng.normal(0, 0.01, (101, 21, 3)), axis=0) + np.linspace(0, 1, 21)[:, None]
    m = motion_from_positions(p, 10.0, KIT21_NAMES, KIT21_PARENTS)   # 10 s at 10 Hz
    cut = motion_windows(m, length=4.0, hop=2.0)
    assert [w.start for w, _ in cut] == [0.0, 2.0, 4.0, 6.0]
    assert all(part.n_frames == 41 for _, part in cut)

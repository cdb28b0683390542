"""Physical plausibility measures on hand-made 21-joint motions, values worked by hand."""
from __future__ import annotations

import math

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.physics import (
    TOES,
    floor_penetration,
    foot_skating,
    physics,
    root_jitter,
    root_kick,
)


def still(T: int = 5) -> np.ndarray:
    """A body with every joint 1 m up except the toes, which rest on the floor."""
    p = np.zeros((T, 21, 3))
    p[..., 1] = 1.0
    p[:, TOES, 1] = 0.0
    return p


def test_foot_skating_by_hand():
    p = still(5)
    assert foot_skating(p, 10.0) == 0.0                 # planted feet do not skate
    p[:, TOES[0], 0] = 0.01 * np.arange(5)              # left toe slides 1 cm a frame
    # 4 steps x 2 toes in contact: left at 0.01 m x 10 Hz = 0.1 m/s, right at 0
    assert foot_skating(p, 10.0) == pytest.approx(0.05)
    p[3:, TOES[1], 1] = 0.2                             # right toe lifted from frame 3 on
    # right toe in contact over steps 0-1 and 1-2 only: (4 x 0.1 + 2 x 0) / 6
    assert foot_skating(p, 10.0) == pytest.approx(0.4 / 6)
    p[:, TOES[0], 0] = 0.5 * np.arange(5)               # 5 m/s: a swing, not a contact
    assert foot_skating(p, 10.0) == pytest.approx(0.0)
    assert foot_skating(p, 10.0, speed=10.0) == pytest.approx(20.0 / 6)
    p[:, :, 1] += 1.0                                    # flying: no contact at all
    assert math.isnan(foot_skating(p, 10.0))
    assert foot_skating(p, 10.0, floor=1.0) == pytest.approx(0.0)


def test_floor_penetration_by_hand():
    p = still(4)
    assert floor_penetration(p) == (0.0, 0.0)
    p[1, 3, 1] = -0.02        # frame 1: a spine joint 2 cm under
    p[2, TOES, 1] = -0.06     # frame 2: both toes 6 cm under (the lowest counts once)
    assert floor_penetration(p) == pytest.approx(((0.02 + 0.06) / 4, 0.06))
    assert floor_penetration(p, floor=-0.05) == pytest.approx((0.01 / 4, 0.01))


def test_root_jitter_by_hand():
    p = still(4)
    assert root_jitter(p) == 0.0 and root_jitter(p[:1]) == 0.0
    p[:, 0, 2] = [0.0, 0.05, 0.10, 0.40]       # steady 5 cm steps, then a 30 cm jump
    p[3, 0, 0] = 0.40                          # ... sideways too: sqrt(0.3^2 + 0.4^2)
    assert root_jitter(p) == pytest.approx(0.5)
    got = physics(p, 30.0)
    assert got["root_jump"] == pytest.approx(0.5) and got["penetration"] == 0.0
    assert set(got) == {"skating", "penetration", "penetration_max", "root_jump", "root_kick"}
    # steps of 5, 5 and 50 cm: the moves change by 0 and sqrt(0.25^2 + 0.4^2) m
    assert got["root_kick"] == pytest.approx(np.hypot(0.25, 0.4))


def test_root_kick_ignores_steady_speed():
    p = still(6)
    p[:, 0, 2] = 0.3 * np.arange(6)            # 30 cm a frame, steadily: a fast run
    assert root_jitter(p) == pytest.approx(0.3) and root_kick(p) == pytest.approx(0.0)
    p[3, 0, 2] += 0.1                          # one frame 10 cm ahead of the path
    assert root_kick(p) == pytest.approx(0.2)  # move +10 then -10 cm: kicks of 0.1, 0.2, 0.1
    assert root_kick(p[:2]) == 0.0


def test_bad_shapes_refused():
    with pytest.raises(MotionlangError, match=r"\(T >= 1, 21, 3\)"):
        root_jitter(np.zeros((3, 20, 3)))
    with pytest.raises(MotionlangError, match="fps"):
        foot_skating(still(), 0.0)

"""features.gait: walking, running and jumping told apart by the feet, whatever the body,
unit, floor or frame rate (issue 41)."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.datasets.synth.corpus import generate_sample
from motionlang.errors import MotionlangError
from motionlang.features.body21 import normalise21
from motionlang.features.gait import foot_contacts, gait, vault_bounce
from motionlang.features.joint_map import positions21


def _sample(index: int):
    s = generate_sample(0, index)
    return normalise21(positions21(s.motion)), s.motion.fps, s.primitives


@pytest.fixture(scope="module")
def walk():
    # sample 6 of seed 0: a single forward walk (tests below check what it is)
    return _sample(6)


@pytest.fixture(scope="module")
def jump():
    return _sample(104)


def test_the_fixtures_are_what_they_say(walk, jump):
    assert [p.action for p in walk[2]] == ["walk"]
    assert [p.action for p in jump[2]] == ["jump"]


def test_a_walk_has_double_support_and_no_flight(walk):
    p, fps, _ = walk
    g = gait(p, fps)
    assert g.action == "walk"
    assert g.double > 0.05 and g.flight < 0.05
    assert g.run_score < 0 and g.jumps == 0
    down = foot_contacts(p, fps)
    assert down.shape == (2, len(p)) and down.any(axis=1).all()


def test_a_two_footed_jump_is_a_jump(jump):
    p, fps, _ = jump
    g = gait(p, fps)
    assert g.jumps >= 1 and g.action == "jump"


def test_standing_still_is_no_gait(walk):
    p, fps, _ = walk
    still = np.repeat(p[:1], 60, axis=0)
    g = gait(still, fps)
    assert g.action is None and g.travelling == 0.0


@pytest.mark.parametrize("scale", [0.7, 1.3, 100.0])
def test_the_body_size_and_unit_do_not_matter(walk, scale):
    p, fps, _ = walk
    a, b = gait(p, fps), gait(p * scale, fps)
    assert b.action == a.action == "walk"
    assert b.flight == pytest.approx(a.flight) and b.double == pytest.approx(a.double)


def test_a_drifting_floor_does_not_lift_the_feet(walk):
    # a capture whose floor rises 4 cm a second, and one sole 3 cm above the other
    p, fps, _ = walk
    q = p.copy()
    q[..., 1] += 0.04 * np.arange(len(q))[:, None] / fps
    q[:, [13, 14, 15], 1] += 0.03            # the left ankle, heel and toe
    a, b = gait(p, fps), gait(q, fps)
    assert b.action == "walk"
    assert abs(b.double - a.double) < 0.05


def test_the_frame_rate_does_not_matter(walk):
    p, fps, _ = walk
    t = np.arange(len(p)) / fps
    t4 = np.arange(0, t[-1], 1 / (4 * fps))
    up = np.stack([np.stack([np.interp(t4, t, p[:, j, k]) for k in range(3)], -1)
                   for j in range(p.shape[1])], 1)
    assert gait(up, 4 * fps).action == "walk"


def test_vault_and_bounce():
    # a root that rises when the feet come together is a walk's vault (negative), one that
    # rises when they spread a run's bounce (positive)
    fps, T = 30.0, 90
    t = np.arange(T) / fps
    p = np.zeros((T, 21, 3))
    spread = np.abs(np.sin(2 * np.pi * t))                       # 0 when the feet pass
    p[:, 13, 2], p[:, 18, 2] = spread / 2, -spread / 2            # LA, RA
    p[:, 0, 1] = 0.9 - 0.02 * spread
    assert vault_bounce(p, fps) < -0.9
    p[:, 0, 1] = 0.9 + 0.02 * spread
    assert vault_bounce(p, fps) > 0.9
    assert np.isnan(vault_bounce(p[:10], fps))


def test_bad_input_is_one_line():
    with pytest.raises(MotionlangError, match=r"\(T, 21, 3\)"):
        gait(np.zeros((10, 20, 3)), 30.0)
    with pytest.raises(MotionlangError, match="fps"):
        gait(np.zeros((10, 21, 3)), 0.0)
    with pytest.raises(MotionlangError, match="finite"):
        gait(np.full((10, 21, 3), np.nan), 30.0)


def test_real_walks_and_jogs_of_cmu_subject_35(shared_data):
    from motionlang.datasets.named import cmu35_walkjog
    trials = cmu35_walkjog(shared_data).trials
    said = [(t.label, gait(normalise21(positions21(t.motion)), t.motion.fps).action)
            for t in trials]
    walks = [a for label, a in said if label == "walk"]
    jogs = [a for label, a in said if label == "jog"]
    assert walks.count("walk") >= 0.9 * len(walks)
    assert jogs.count("run") >= 0.9 * len(jogs)


def _hop(stand, fps, *, lift_left_first: float, flight: float):
    """Standing, then (optionally) the left foot lifted for a while, then the whole body in
    the air for ``flight`` s, then standing again: (T, 21, 3)."""
    n1, n2, n3 = int(0.6 * fps), int(lift_left_first * fps), int(flight * fps)
    p = np.repeat(stand[None], n1 + n2 + n3 + int(0.6 * fps), axis=0)
    p[n1:n1 + n2, [13, 14, 15], 1] += 0.2               # the left ankle, heel and toe
    p[n1 + n2:n1 + n2 + n3, :, 1] += 0.3                # everything off the floor
    return p


def test_a_long_flight_from_one_foot_is_a_leap(walk):
    p, fps, _ = walk
    stand = p[0]
    assert gait(_hop(stand, fps, lift_left_first=0.0, flight=0.2), fps).jumps == 1
    assert gait(_hop(stand, fps, lift_left_first=0.3, flight=0.2), fps).jumps == 0
    assert gait(_hop(stand, fps, lift_left_first=0.3, flight=0.45), fps).jumps == 1

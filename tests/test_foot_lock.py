"""Foot contact clean-up (features.foot_lock) on hand-made 21-joint bodies. The lock's own
steps are tested with ``anchor=False`` (the root step would otherwise have stopped the drift
they are given before the lock sees it); the root step has tests of its own."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.physics import floor_penetration, foot_skating
from motionlang.features.foot_lock import LEGS, anchor_root, contacts, lock_feet
from motionlang.features.joint_map import KIT21_NAMES, bone_lengths21


def standing(T: int) -> np.ndarray:
    """(T, 21, 3): a body standing with slightly bent knees, toes on the floor."""
    p = np.zeros((T, 21, 3))
    p[:, :, 1] = 1.2                                   # trunk and arms: high up
    p[:, 0] = (0.0, 0.95, 0.0)                         # root
    for (hip, knee, ankle, mid, toe), x in zip(LEGS, (0.1, -0.1)):
        p[:, hip] = (x, 0.9, 0.0)
        p[:, knee] = (x, 0.5, 0.06)
        p[:, ankle] = (x, 0.1, 0.0)
        p[:, mid] = (x, 0.03, 0.08)
        p[:, toe] = (x, 0.01, 0.15)
    return p


def test_contacts_by_hand():
    toe = np.zeros((8, 3))
    toe[:, 1] = [0.0, 0.0, 0.0, 0.3, 0.3, 0.0, 0.0, 0.0]    # lifted at frames 3-4
    assert contacts(toe, 10.0) == [(0, 2), (5, 7)]
    assert contacts(toe, 10.0, min_frames=4) == []
    toe[5:, 0] = 0.5 * np.arange(3)                          # 5 m/s: a swing, not a contact
    assert contacts(toe, 10.0) == [(0, 2)]
    assert contacts(toe, 10.0, speed=10.0) == [(0, 2), (5, 7)]


def test_sliding_body_gets_planted_feet_and_keeps_its_bones():
    T = 20
    p = standing(T)
    p[:, :, 0] += 0.01 * np.arange(T)[:, None]               # everything drifts 0.1 m/s
    assert foot_skating(p, 10.0) == pytest.approx(0.1)
    q = lock_feet(p, 10.0, anchor=False)
    assert foot_skating(q, 10.0) == pytest.approx(0.0, abs=1e-9)
    # the toes stay at their mean position over the contact (the whole motion)
    for *_, toe in LEGS:
        assert np.allclose(q[:, toe, [0, 2]], p[:, toe, [0, 2]].mean(axis=0))
    # hips, root, trunk and arms untouched; the legs keep every bone's length
    legs = {j for leg in LEGS for j in leg[1:]}
    rest = [j for j in range(21) if j not in legs]
    assert np.array_equal(q[:, rest], p[:, rest])
    assert np.allclose(bone_lengths21(q), bone_lengths21(p))
    # the knee still bends forward (+Z), as in the original pose
    knee = KIT21_NAMES.index("LK")
    assert (q[:, knee, 2] > 0).all()
    assert p.shape == q.shape and not np.shares_memory(p, q)


def test_a_contact_with_pinned_frames_is_held_where_the_foot_is_on_them():
    T = 20
    p = standing(T)
    p[:, :, 0] += 0.005 * np.arange(T)[:, None]              # drifts 5 cm a second
    pinned = np.zeros(T, dtype=bool)
    pinned[:4] = True                                         # the foot must stay here
    q = lock_feet(p, 10.0, anchor=False, pinned=pinned)
    assert foot_skating(q, 10.0) == pytest.approx(0.0, abs=1e-9)
    for *_, toe in LEGS:   # held at its mean over the pinned frames, not over the contact
        assert np.allclose(q[:, toe, [0, 2]], p[:4, toe, [0, 2]].mean(axis=0))
    assert np.allclose(lock_feet(p, 10.0, anchor=False, pinned=np.zeros(T, dtype=bool)),
                       lock_feet(p, 10.0, anchor=False))


def test_lock_fades_out_where_the_foot_is_lifted():
    T = 16
    p = standing(T)
    p[:, :, 0] += 0.01 * np.arange(T)[:, None]
    hip, knee, ankle, mid, toe = LEGS[0]
    p[8:, [ankle, mid, toe], 1] += 0.3                     # left foot lifted from frame 8
    p[8:, knee, 1] += 0.15
    q = lock_feet(p, 10.0, blend=2, anchor=False)
    # frames 0-7 held at their mean toe position; 8-9 fade; 10 on as decoded
    left = q[:, toe, 0] - p[:, toe, 0]
    mean = p[:8, toe, 0].mean()
    assert np.allclose(q[:8, toe, 0], mean)
    assert np.allclose(left[10:], 0.0)
    last = mean - p[7, toe, 0]
    assert left[8] == pytest.approx(last * 2 / 3) and left[9] == pytest.approx(last / 3)


def test_out_of_reach_ankle_is_pulled_back_not_stretched():
    T = 30
    p = standing(T)
    p[:, :, 0] += 0.05 * np.arange(T)[:, None]             # 0.5 m/s: 1.45 m over the run
    q = lock_feet(p, 10.0, max_shift=1.0, reach=10.0, anchor=False)   # held: a glide
    assert np.allclose(bone_lengths21(q), bone_lengths21(p))
    hip, knee, ankle, *_ = LEGS[0]
    leg = np.linalg.norm(q[:, ankle] - q[:, hip], axis=-1)
    full = (np.linalg.norm(p[0, knee] - p[0, hip]) + np.linalg.norm(p[0, ankle] - p[0, knee]))
    assert (leg <= full + 1e-9).all() and leg.max() > 0.99 * full


@pytest.mark.parametrize("bad, fps", [(np.zeros((4, 20, 3)), 10.0), (np.zeros((4, 21, 3)), 0.0)])
def test_bad_input_is_an_error(bad, fps):
    with pytest.raises(MotionlangError, match="lock_feet"):
        lock_feet(bad, fps)


def test_frames_without_a_shift_and_collapsed_legs_are_left_alone():
    T = 16
    p = standing(T)
    p[:, :, 0] += 0.01 * np.arange(T)[:, None]
    hip, knee, ankle, mid, toe = LEGS[0]
    p[8:, [ankle, mid, toe], 1] += 0.3                     # lifted from frame 8: no shift
    p[8:, knee, 1] += 0.15                                 # from frame 10 on
    q = lock_feet(p, 10.0, blend=2, anchor=False)
    assert np.array_equal(q[10:, [knee, ankle, mid, toe]], p[10:, [knee, ankle, mid, toe]])
    flat = np.zeros((5, 21, 3))                            # every joint at one point
    assert np.array_equal(lock_feet(flat, 12.5), flat)


def test_a_straight_leg_bends_forward_when_its_foot_is_held_back():
    T = 12
    p = standing(T)
    for _hip, knee, _ankle, *_ in LEGS:                      # straight legs
        p[:, knee, 2] = 0.0
    p[:, :, 2] += 0.01 * np.arange(T)[:, None]             # drifting forward (+Z, the facing)
    q = lock_feet(p, 10.0, anchor=False)
    for hip, knee, ankle, *_ in LEGS:
        # the knee ends up in front of the hip-ankle line, never behind it
        d, k = q[:, ankle] - q[:, hip], q[:, knee] - q[:, hip]
        cross = d[:, 1] * k[:, 2] - d[:, 2] * k[:, 1]      # sign of the bend about the x axis
        assert (cross <= 1e-9).all()
    assert np.allclose(bone_lengths21(q), bone_lengths21(p))


def test_a_glide_is_left_alone():
    """A toe dragged 1.5 m along the floor is not a plant: holding it would stretch the leg
    out behind the body."""
    T = 30
    p = standing(T)
    p[:, :, 2] += 0.05 * np.arange(T)[:, None]             # 0.5 m/s, toes down throughout
    assert np.array_equal(lock_feet(p, 10.0, anchor=False), p)
    assert not np.array_equal(lock_feet(p, 10.0, max_shift=1.0, reach=10.0, anchor=False), p)


def test_a_hold_the_leg_cannot_reach_is_left_alone():
    T = 12
    p = standing(T)
    p[:, :, 2] += 0.02 * np.arange(T)[:, None]             # 11 cm either side of the mean
    q = lock_feet(p, 10.0, anchor=False)                   # bent knees reach that: held
    assert foot_skating(q, 10.0) == pytest.approx(0.0, abs=1e-9)
    # a leg reaching half as far
    assert np.array_equal(lock_feet(p, 10.0, reach=0.5, anchor=False), p)


def test_a_straight_stance_leg_is_held_within_a_reach_tolerance():
    T = 12
    p = standing(T)
    for leg in LEGS:
        p[:, leg[1], 2] = 0.0                              # knees straight: reach exactly used
    p[:, [j for leg in LEGS for j in leg[2:]], 0] += 0.004 * np.arange(T)[:, None]
    assert foot_skating(p, 10.0) == pytest.approx(0.04)    # feet slide 4 cm/s under the hips
    assert np.array_equal(lock_feet(p, 10.0, anchor=False), p)   # just out of reach: a glide
    q = lock_feet(p, 10.0, anchor=False, reach=1.05)
    # held: the IK stops the ankle at 99.9 % of the leg, and the toe slides by what is left
    assert foot_skating(q, 10.0) < 0.1 * foot_skating(p, 10.0)
    assert np.allclose(bone_lengths21(q), bone_lengths21(p))


def test_a_foot_under_the_floor_is_raised_onto_it_and_the_lift_fades():
    T = 16
    p = standing(T)
    hip, knee, ankle, mid, toe = LEGS[0]
    p[6:10, [ankle, mid, toe], 1] -= 0.02                  # toe 1 cm under the floor, frames 6-9
    q = lock_feet(p, 10.0, blend=2)
    assert floor_penetration(p)[1] == pytest.approx(0.01)
    assert floor_penetration(q)[1] < 1e-12                 # on the floor (to rounding)
    lift = q[:, toe, 1] - p[:, toe, 1]
    # exactly the depth where it sank, a third less per frame either side, nothing beyond
    expect = np.zeros(T)
    expect[6:10] = 0.01
    expect[[5, 10]], expect[[4, 11]] = 0.01 * 2 / 3, 0.01 / 3
    assert np.allclose(lift, expect)
    # the whole foot rises with the ankle, the hip stays, the bones keep their lengths
    assert np.allclose(q[:, [ankle, mid], 1] - p[:, [ankle, mid], 1], expect[:, None])
    assert np.allclose(q[:, [ankle, mid, toe]][..., [0, 2]], p[:, [ankle, mid, toe]][..., [0, 2]])
    assert np.array_equal(q[:, hip], p[:, hip])
    assert np.allclose(bone_lengths21(q), bone_lengths21(p))
    # the other leg, above the floor, is untouched
    assert np.array_equal(q[:, list(LEGS[1])], p[:, list(LEGS[1])])


def test_a_sunk_foot_lands_on_the_floor_not_above_it_and_the_lock_still_holds():
    """Depths that differ frame to frame: each sunk frame is raised by its own depth (a
    deeper neighbour's fade does not lift it off the floor); on a drifting body the planted
    toe is both held and raised."""
    T = 12
    p = standing(T)
    p[:, :, 0] += 0.01 * np.arange(T)[:, None]              # drifting: the toes are held
    hip, knee, ankle, mid, toe = LEGS[1]
    p[4:7, [ankle, mid, toe], 1] -= np.array([0.02, 0.04, 0.02])[:, None]   # toe 1, 3, 1 cm under
    q = lock_feet(p, 10.0, blend=2)
    assert np.allclose(q[4:7, toe, 1], 0.0)                 # on the floor, not above it
    assert np.allclose(q[[2, 3, 7, 8], toe, 1] - p[[2, 3, 7, 8], toe, 1],
                       [0.01 / 3, 0.01, 0.01, 0.01 / 3])   # fades, 2 frames out (3 cm, 1 cm)
    assert np.allclose(q[[0, 1, 9, 10, 11], toe, 1], p[[0, 1, 9, 10, 11], toe, 1])
    assert foot_skating(q, 10.0) == pytest.approx(0.0, abs=1e-9)
    assert floor_penetration(q)[1] < 1e-12
    assert np.allclose(bone_lengths21(q), bone_lengths21(p))


def test_a_body_drifting_on_its_feet_stands_still_as_a_whole():
    """The root step: a body whose feet are down while it drifts is moved back by its feet's
    step, every joint alike, so it stands where it started, pose and bones unchanged."""
    T = 20
    p = standing(T)
    p[:, :, 0] += 0.01 * np.arange(T)[:, None]               # everything drifts 0.1 m/s
    for window in (0.0, 0.4):
        q = anchor_root(p, 10.0, window=window)
        assert np.allclose(q, standing(T))                    # back where frame 0 stood
        assert foot_skating(q, 10.0) == pytest.approx(0.0, abs=1e-9)
    q = lock_feet(p, 10.0)                                    # the lock runs it first
    assert np.allclose(q, standing(T))
    assert p.shape == q.shape and not np.shares_memory(p, q)


def test_a_body_in_the_air_keeps_its_path():
    T = 12
    p = standing(T)
    p[:, :, 1] += 0.3                                         # feet 30 cm up: no contact
    p[:, :, 2] += 0.05 * np.arange(T)[:, None]
    assert np.array_equal(anchor_root(p, 10.0), p)
    assert np.array_equal(lock_feet(p, 10.0), p)


def test_the_body_follows_the_foot_that_is_down_or_the_mean_of_both():
    T = 10
    p = standing(T)
    lt, rt = LEGS[0][4], LEGS[1][4]
    p[:, :, 2] += 0.03 * np.arange(T)[:, None]               # the body walks at 0.3 m/s
    p[:, rt, 1] += 0.2                                        # the right foot is up (a swing)
    q = anchor_root(p, 10.0, window=0.0)
    # the left toe stays where it was at frame 0, the whole body moved with it
    assert np.allclose(q[:, lt], p[0, lt])
    assert np.allclose(q - q[:, :1], p - p[:, :1])
    # both down, the left toe sliding 0.02 m per frame more than the right: the mean step
    p = standing(T)
    p[:, :, 2] += 0.03 * np.arange(T)[:, None]
    p[:, [j for j in LEGS[0][2:]], 2] += 0.02 * np.arange(T)[:, None]
    q = anchor_root(p, 10.0, window=0.0)
    assert np.allclose(np.diff(q[:, lt, 2]), 0.01) and np.allclose(np.diff(q[:, rt, 2]), -0.01)


def test_the_correction_is_spread_where_a_contact_begins():
    """The foot lands at frame 6 of a body travelling 0.5 m/s: without a window the root stops
    dead in one frame step, with one it slows over several."""
    T = 14
    p = standing(T)
    p[:, :, 2] += 0.05 * np.arange(T)[:, None]
    p[:6, :, 1] += 0.3                                        # in the air until frame 6
    for window, largest in ((0.0, 0.05), (0.5, 0.05 / 5)):
        root = anchor_root(p, 10.0, window=window)[:, 0, 2]
        assert np.abs(np.diff(root, n=2)).max() == pytest.approx(largest)
    assert np.array_equal(anchor_root(p, 10.0)[:1], p[:1])    # frame 0 stays


@pytest.mark.parametrize("bad,fps", [(np.zeros((5, 20, 3)), 12.5), (np.zeros((5, 21, 3)), 0)])
def test_anchor_root_bad_input_is_an_error(bad, fps):
    with pytest.raises(MotionlangError, match="anchor_root"):
        anchor_root(bad, fps)


def test_the_body_stops_exactly_on_the_contact_steps():
    """Feet down on frames 6-9 of 14 (steps 6-7, 7-8, 8-9) of a body travelling 0.05 m a
    frame: unsmoothed, the root stands still on exactly those frames; smoothed, it slows
    earlier and later but the total correction is the same three steps."""
    T = 14
    p = standing(T)
    p[:, :, 2] += 0.05 * np.arange(T)[:, None]
    up = [t for t in range(T) if not 6 <= t <= 9]
    p[up, :, 1] += 0.3
    root = anchor_root(p, 10.0, window=0.0)[:, 0, 2]
    moves = np.diff(root)
    assert np.allclose(moves[6:9], 0.0) and np.allclose(np.delete(moves, [6, 7, 8]), 0.05)
    smooth = anchor_root(p, 10.0, window=0.5)[:, 0, 2]
    assert smooth[-1] == pytest.approx(root[-1])             # 13 * 0.05 - 3 * 0.05
    assert np.allclose(np.diff(smooth)[:4], 0.05) and np.allclose(np.diff(smooth)[11:], 0.05)


def test_a_contact_at_the_start_is_not_over_corrected():
    T = 12
    p = standing(T)
    p[:, :, 2] += 0.05 * np.arange(T)[:, None]
    p[2:, :, 1] += 0.3                                        # down on frames 0-1 only
    for window in (0.0, 0.5, 1.0):
        q = anchor_root(p, 10.0, window=window)
        back = (p[-1, 0, 2] - p[0, 0, 2]) - (q[-1, 0, 2] - q[0, 0, 2])
        assert 0.0 < back <= 0.05 + 1e-12                     # one step's worth at most


def test_a_nan_outside_a_contact_stays_in_its_frame():
    T = 10
    p = standing(T)
    p[:, :, 0] += 0.01 * np.arange(T)[:, None]
    lt = LEGS[0][4]
    p[3, lt] = np.nan
    q = anchor_root(p, 10.0)
    assert np.isnan(q[3, lt]).all()
    assert np.isfinite(np.delete(q, 3, axis=0)).all() and np.isfinite(q[:, :lt]).all()


def test_by_default_the_body_stops_with_a_dragged_foot():
    """A toe dragged along the floor slower than ``speed`` is a contact for the root step:
    the body it belongs to stops (the lock alone leaves such a glide as it is)."""
    T = 30
    p = standing(T)
    p[:, :, 2] += 0.05 * np.arange(T)[:, None]               # 0.5 m/s, toes down throughout
    q = lock_feet(p, 10.0)
    assert np.allclose(q, standing(T))
    assert np.array_equal(lock_feet(p, 10.0, anchor=False), p)

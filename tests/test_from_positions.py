"""Joint positions -> joint angles (kinematics.from_positions): hand-worked rotations, exact
reconstruction of a rigid skeleton's motion, bone lengths, BVH round trip, bad input."""
import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS
from motionlang.formats import read_motion, write_motion
from motionlang.kinematics import Motion
from motionlang.kinematics.from_positions import (
    ZXY,
    motion_from_positions,
    position_error,
    skeleton_from_positions,
)

# a standing 21-joint body, metres, Y up, facing +Z (left = +X)
REST = np.array([
    [0, 1.00, 0], [0, 1.07, 0], [0, 1.18, 0], [0, 1.45, 0.02], [0, 1.55, 0.02],     # trunk
    [0.18, 1.42, 0], [0.20, 1.12, 0], [0.21, 0.87, 0.02],                           # left arm
    [-0.18, 1.42, 0], [-0.20, 1.12, 0], [-0.21, 0.87, 0.02],                        # right arm
    [0.09, 0.98, 0], [0.10, 0.55, 0], [0.10, 0.09, 0], [0.10, 0.03, 0.08], [0.10, 0.02, 0.15],
    [-0.09, 0.98, 0], [-0.10, 0.55, 0], [-0.10, 0.09, 0], [-0.10, 0.03, 0.08],
    [-0.10, 0.02, 0.15]])


def test_two_joints_by_hand():
    # a bone along +Y turned to +X: a quarter turn about Z, clockwise seen from +Z
    p = np.array([[[0, 0, 0], [0, 1, 0]], [[0, 0, 0], [1, 0, 0]], [[2, 0, 0], [2, 0, 2]]], float)
    m = motion_from_positions(p, 10.0, ["a", "b"], [-1, 0])
    assert m.skeleton.joints[1].offset == pytest.approx([0, 1, 0])   # median length 1
    np.testing.assert_allclose(m.root_rotation[0], [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(m.root_rotation[1], [-np.pi / 2, 0, 0], atol=1e-12)   # Z X Y
    # +Y to +Z: a quarter turn about +X
    np.testing.assert_allclose(m.root_rotation[2], [0, np.pi / 2, 0], atol=1e-12)
    np.testing.assert_allclose(m.root_translation, p[:, 0])
    # direction kept, length the median (1): the third frame's 2 m bone comes out 1 m
    np.testing.assert_allclose(m.positions()[2, 1], [2, 0, 1], atol=1e-12)
    np.testing.assert_allclose(position_error(m, p)[:, 1], [0, 0, 1], atol=1e-12)


def test_opposite_bone_is_half_a_turn():
    p = np.array([[[0, 0, 0], [0, 1, 0]], [[0, 0, 0], [0, -1, 0]]], float)
    m = motion_from_positions(p, 10.0, ["a", "b"], [-1, 0])
    np.testing.assert_allclose(m.positions(), p, atol=1e-12)


def test_angles_unwrapped():
    # two turns about +Y in 40 frames: the Y angle climbs to 4 pi instead of wrapping
    theta = np.linspace(0, 4 * np.pi, 40)
    c, s = np.cos(theta), np.sin(theta)
    p = np.zeros((40, 3, 3))
    p[:, 1] = np.stack([c, 0 * c, -s], 1)      # R_y(theta) (1, 0, 0)
    p[:, 2] = [0, 1, 0]
    m = motion_from_positions(p, 10.0, ["a", "b", "c"], [-1, 0, 0])
    np.testing.assert_allclose(m.root_rotation[:, 2], theta, atol=1e-9)
    np.testing.assert_allclose(m.root_rotation[:, :2], 0, atol=1e-9)


def test_no_twist_when_a_bone_turns_past_half_round():
    # a bone points down at rest, turns up through the front, then circles 3 degrees off
    # straight up: its frame should turn as little as the bone does (a swing from the rest
    # direction each frame would spin it by the circle's 6 degrees a frame about the bone)
    a = 0.05
    phi = np.linspace(0, np.pi - a, 60)
    psi = np.linspace(np.pi / 2, 2.5 * np.pi, 61)[1:]
    d = np.concatenate([np.stack([0 * phi, -np.cos(phi), np.sin(phi)], 1),
                        np.stack([np.sin(a) * np.cos(psi), np.cos(a) + 0 * psi,
                                  np.sin(a) * np.sin(psi)], 1)])
    p = np.zeros((len(d), 2, 3))
    p[:, 1] = d
    m = motion_from_positions(p, 10.0, ["a", "b"], [-1, 0])
    np.testing.assert_allclose(m.positions(), p, atol=1e-9)
    R, _ = m.global_transforms()
    step = np.einsum("tji,tjk->tik", R[:-1, 0], R[1:, 0])     # frame-to-frame turn
    turn = np.arccos(np.clip((np.trace(step, axis1=1, axis2=2) - 1) / 2, -1, 1))
    bone = np.arccos(np.clip(np.sum(d[:-1] * d[1:], 1), -1, 1))
    np.testing.assert_allclose(turn, bone, atol=1e-6)           # the smallest turn: no twist


def _rigid_motion(T=40, seed=0) -> tuple[Motion, np.ndarray]:
    """A smooth random motion of a skeleton built on REST, and its joint positions."""
    sk = skeleton_from_positions(REST[None], KIT21_NAMES, KIT21_PARENTS)
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, T)[:, None]
    ang = 0.8 * np.sin(2 * np.pi * (t * rng.uniform(0.5, 2, sk.ndof) + rng.uniform(0, 1, sk.ndof)))
    root_rot = np.concatenate([3 * t, 0.3 * np.sin(6 * t), 0.2 * t], axis=1)
    m = Motion(sk, 25.0, np.concatenate([t, 1 + 0 * t, 2 * t], axis=1), root_rot, ang)
    return m, m.positions()


def test_rigid_motion_comes_back_exactly():
    truth, p = _rigid_motion()
    m = motion_from_positions(p, truth.fps, KIT21_NAMES, KIT21_PARENTS, rest=REST)
    # lengths are constant, so the fit is exact: every joint to a micrometre
    assert position_error(m, p).max() < 1e-6
    # the multi-child nodes (root, neck) get the true rotation, twist included
    Rt, _ = truth.global_transforms()
    Rm, _ = m.global_transforms()
    for j in (0, KIT21_NAMES.index("BLN")):
        np.testing.assert_allclose(Rm[:, j], Rt[:, j], atol=1e-9)
    # leaves are End Sites without DOFs; the others turn on Z X Y
    sk = m.skeleton
    assert sk.joints[KIT21_NAMES.index("LW")].ndof == 0
    assert np.array_equal(sk.joints[KIT21_NAMES.index("LE")].axes, ZXY)


def test_bvh_round_trip(tmp_path):
    _, p = _rigid_motion(T=12, seed=3)
    m = motion_from_positions(p, 12.5, KIT21_NAMES, KIT21_PARENTS)   # rest: the first frame
    write_motion(m, tmp_path / "x.bvh")
    back = read_motion(tmp_path / "x.bvh")
    assert back.fps == pytest.approx(12.5) and back.n_frames == 12
    # the BVH holds the same joints (leaves as End Sites named after their parent)
    named = [back.skeleton.index(n) for n in KIT21_NAMES if n in back.skeleton]
    assert len(named) == 16
    ours = [KIT21_NAMES.index(back.skeleton.names[i]) for i in named]
    np.testing.assert_allclose(back.positions()[:, named], p[:, ours], atol=1e-6)
    np.testing.assert_allclose(back.positions()[:, back.skeleton.index("LE_end")],
                               p[:, KIT21_NAMES.index("LW")], atol=1e-6)


def test_bone_lengths_are_medians():
    _, p = _rigid_motion(T=9, seed=1)
    q = p.copy()
    k = KIT21_NAMES.index("LK")
    q[4, k:k + 4] += (q[4, k] - q[4, k - 1]) * 0.3      # the thigh of frame 4 30 % longer
    m = motion_from_positions(q, 25.0, KIT21_NAMES, KIT21_PARENTS)
    thigh = np.linalg.norm(p[0, k] - p[0, k - 1])
    assert np.linalg.norm(m.skeleton.joints[k].offset) == pytest.approx(thigh)
    err = position_error(m, q)
    assert err[4, k] == pytest.approx(0.3 * thigh) and np.delete(err, 4, 0).max() < 1e-6


def test_bad_input():
    _, p = _rigid_motion(T=5)
    with pytest.raises(MotionlangError, match=r"\(T, J, 3\)"):
        motion_from_positions(p[0], 25.0, KIT21_NAMES, KIT21_PARENTS)
    with pytest.raises(MotionlangError, match="20 names"):
        motion_from_positions(p, 25.0, KIT21_NAMES[:-1], KIT21_PARENTS)
    q = p.copy()
    q[3, 7, 1] = np.nan
    with pytest.raises(MotionlangError, match="frame 3"):
        motion_from_positions(q, 25.0, KIT21_NAMES, KIT21_PARENTS)
    with pytest.raises(MotionlangError, match=r"root \(-1\) first"):
        motion_from_positions(p[:, :2], 25.0, ["a", "b"], [0, -1])
    with pytest.raises(MotionlangError, match="joint 'LW'"):                 # names the joint
        motion_from_positions(q, 25.0, KIT21_NAMES, KIT21_PARENTS)
    q = p.copy()
    q[:, KIT21_NAMES.index("LW")] = q[:, KIT21_NAMES.index("LE")]
    with pytest.raises(MotionlangError, match="'LW' sits on its parent 'LE' in every frame"):
        motion_from_positions(q, 25.0, KIT21_NAMES, KIT21_PARENTS)
    rest = REST.copy()
    rest[6] = rest[5]
    with pytest.raises(MotionlangError, match="'LE' sits on its parent 'LS'"):
        motion_from_positions(p, 25.0, KIT21_NAMES, KIT21_PARENTS, rest=rest)


def test_bone_without_length_in_the_first_frame():
    _, p = _rigid_motion(T=6, seed=2)
    q = p.copy()
    k = KIT21_NAMES.index("LW")
    q[0, k] = q[0, k - 1]                  # the wrist on the elbow in frame 0 only
    m = motion_from_positions(q, 25.0, KIT21_NAMES, KIT21_PARENTS)
    # its rest direction is taken from frame 1, and frames 1.. come out exact
    assert position_error(m, q)[1:].max() < 1e-6


def test_children_on_one_line_fall_back_to_one_bone():
    # a root whose two children lie on one line through it, with a little noise: the
    # least-squares rotation about that line is undetermined; one-bone fitting keeps it still
    rng = np.random.default_rng(0)
    T = 30
    p = np.zeros((T, 3, 3))
    p[:, 1], p[:, 2] = [0.1, 0, 0], [-0.1, 0, 0]
    p[:, 1:] += rng.normal(0, 1e-7, (T, 2, 3))
    m = motion_from_positions(p, 10.0, ["root", "a", "b"], [-1, 0, 0])
    R, _ = m.global_transforms()
    step = np.einsum("tji,tjk->tik", R[:-1, 0], R[1:, 0])
    assert np.arccos(np.clip((np.trace(step, axis1=1, axis2=2) - 1) / 2, -1, 1)).max() < 1e-4

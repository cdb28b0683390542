import numpy as np
import pytest

from helpers.mocap import tiny_skeleton
from motionlang.errors import MotionFormatError, MotionlangError, SkeletonError
from motionlang.kinematics import Motion, concatenate


def test_fk_by_hand():
    sk = tiny_skeleton()
    angles = np.zeros((1, sk.ndof))
    angles[0, sk.dof_slice("LeftLeg")] = np.pi / 2  # knee bent 90 degrees about +x
    m = Motion(sk, 10, np.array([[0.0, 2.0, 0.0]]), np.zeros((1, 3)), angles)
    p = m.positions()[0]
    assert np.allclose(p[sk.index("LeftLeg")], [0.1, 1.0, 0.0])
    # rotating (0,-1,0) by +90 deg about x gives (0,0,-1)
    assert np.allclose(p[sk.index("LeftFoot")], [0.1, 1.0, -1.0])
    assert np.allclose(p[sk.index("RightFoot")], [-0.1, 0.0, 0.0])


def test_root_rotation_turns_body():
    sk = tiny_skeleton()
    # root axes z, x, y: a yaw of 90 deg is the third angle
    m = Motion(sk, 10, np.zeros((1, 3)), np.array([[0, 0, np.pi / 2]]), np.zeros((1, sk.ndof)))
    p = m.positions()[0]
    assert np.allclose(p[sk.index("LeftUpLeg")], [0, 0, -0.1])


def test_mirror_twice_is_identity_and_swaps_sides(tiny_motion):
    m2 = tiny_motion.mirror()
    p, q = tiny_motion.positions(), m2.positions()
    sk = tiny_motion.skeleton
    L, R = sk.index("LeftFoot"), sk.index("RightFoot")
    flip = np.array([-1, 1, 1])
    assert np.allclose(q[:, L], p[:, R] * flip)
    assert np.allclose(q[:, sk.index("Spine")], p[:, sk.index("Spine")] * flip)
    back = m2.mirror()
    assert np.array_equal(back.joint_angles, tiny_motion.joint_angles)
    assert np.array_equal(back.root_rotation, tiny_motion.root_rotation)


def test_slice_and_resample(tiny_motion):
    half = tiny_motion[1::2]
    assert half.fps == 15 and half.n_frames == 10
    assert np.array_equal(half.joint_angles, tiny_motion.joint_angles[1::2])
    dec = tiny_motion.resample(10)
    assert dec.n_frames == 7
    assert np.allclose(dec.joint_angles, tiny_motion.joint_angles[::3])
    up = tiny_motion.resample(60)
    assert up.n_frames == 39
    mid = (tiny_motion.root_translation[0] + tiny_motion.root_translation[1]) / 2
    assert np.allclose(up.root_translation[1], mid)


def test_resample_unwraps_angles():
    sk = tiny_skeleton()
    ang = np.zeros((2, sk.ndof))
    ang[:, 0] = [np.pi - 0.1, -np.pi + 0.1]  # crossing +-pi: the short way is 0.2 rad
    m = Motion(sk, 10, np.zeros((2, 3)), np.zeros((2, 3)), ang).resample(20)
    assert np.isclose(abs(np.cos(m.joint_angles[1, 0]) + 1), 0, atol=1e-12)


def test_nan_frame_is_reported():
    sk = tiny_skeleton()
    ang = np.zeros((5, sk.ndof))
    ang[3, 2] = np.nan
    with pytest.raises(MotionFormatError, match="frame 3"):
        Motion(sk, 10, np.zeros((5, 3)), np.zeros((5, 3)), ang, name="bad")


def test_zero_length_and_shape_errors():
    sk = tiny_skeleton()
    with pytest.raises(MotionFormatError, match="no frames"):
        Motion(sk, 10, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, sk.ndof)))
    with pytest.raises(MotionFormatError, match="joint_angles"):
        Motion(sk, 10, np.zeros((2, 3)), np.zeros((2, 3)), np.zeros((2, 1)))


def test_unknown_joint_and_concatenate(tiny_motion):
    with pytest.raises(SkeletonError, match="nope"):
        tiny_motion.skeleton.index("nope")
    both = concatenate([tiny_motion, tiny_motion[:5]])
    assert both.n_frames == 25


def test_positions_of_some_joints_match_all_joints(tiny_motion):
    everything = tiny_motion.positions()
    for joints in ([3], [0], [6, 2], [7, 3, 5]):
        assert np.array_equal(tiny_motion.positions(joints), everything[:, joints])


def test_between_keeps_both_ends_and_names_an_empty_span():
    sk = tiny_skeleton()
    m = Motion(sk, 10, np.zeros((20, 3)), np.zeros((20, 3)), np.zeros((20, sk.ndof)),
               meta={"path": "walk.bvh"})
    assert m.between() is m
    assert m.between(0.5, 1.0).n_frames == 6           # frames 5..10, both ends
    assert m.between(end=0.2).n_frames == 3 and m.between(1.5).n_frames == 5
    with pytest.raises(MotionlangError, match=r"walk.bvh: no frames between 3 s and the end "
                                              r"\(motion lasts 2.00 s\)"):
        m.between(3.0)
    with pytest.raises(MotionlangError, match="no frames between 1 s and 0.5 s"):
        m.between(1.0, 0.5)

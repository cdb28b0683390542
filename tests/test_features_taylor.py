import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import synthetic_mmm, tiny_skeleton, turn
from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features import TaylorFeatures, features_from_dict
from motionlang.features.root import rot_y
from motionlang.formats.asf_amc import read_asf_amc
from motionlang.kinematics import Motion


@pytest.fixture(scope="module")
def cmu():
    m = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    return TaylorFeatures().fit([m]), m


def test_layout_drops_constant_dims(cmu):
    f, m = cmu
    x = f.encode(m)
    assert f.fps == 30.0 and x.shape == (len(m[::4]), f.dim)
    # one-DOF knee: only the x component of its exp-map moves; a bone without motion in
    # the take (e.g. the clavicles) disappears entirely
    assert "ltibia_rx" in f.names and "ltibia_ry" not in f.names
    assert not any(n.startswith("lclavicle") for n in f.names)
    assert f.names[:6] == ["root_vx", "root_vz", "root_dyaw", "root_height", "root_pitch",
                           "root_roll"]
    assert np.allclose(x.mean(0), 0, atol=1e-5) and np.allclose(x.std(0), 1, atol=1e-4)


def test_features_motion_features(cmu):
    f, m = cmu
    x = f.encode(m)
    back = f.decode(x)
    assert back.fps == 30.0 and len(back) == len(x)
    assert np.abs(f.encode(back) - x).max() < 1e-5


def test_motion_features_motion(cmu):
    f, m = cmu
    sub = m[::4]
    out = f.decode(f.encode(m), start=f.start(m))
    assert np.abs(out.positions() - sub.positions()).max() < 1e-5
    # bones the take never moves get back their constant angles
    sk = m.skeleton
    cl = sk.dof_slice("lclavicle")
    assert np.allclose(out.joint_angles[:, cl], sub.joint_angles[:, cl], atol=1e-9)
    # from the default start the motion is the same up to a turn and shift on the ground
    p0, p = f.decode(f.encode(m)).positions(), sub.positions()
    yaw0 = f.start(m)[2]
    moved = p0 @ rot_y(yaw0).T + (p[0, 0] - p0[0, 0] @ rot_y(yaw0).T) * [1, 0, 1]
    assert np.abs(moved - p).max() < 1e-5


def test_heading_invariance_on_tiny_skeleton():
    rng = np.random.default_rng(0)
    sk = tiny_skeleton()
    T = 40
    t = np.arange(T) / 120.0
    m = Motion(sk, 120.0, np.column_stack([t, 1 + 0.1 * np.sin(9 * t), 2 * t]),
               np.column_stack([0.1 * np.sin(5 * t), 0.05 * t, t]),
               0.3 * np.sin(7 * t[:, None] + rng.uniform(0, 6, sk.ndof)))
    f = TaylorFeatures().fit([m])
    assert np.allclose(f.encode(turn(m, 1.3, -2.0, 0.5)), f.encode(m), atol=1e-4)
    out = f.decode(f.encode(m), start=f.start(m))
    assert np.abs(out.positions() - m[::4].positions()).max() < 1e-5


def test_persistence_needs_a_skeleton_to_decode(cmu, tmp_path):
    f, m = cmu
    f.save(tmp_path / "taylor.json")
    g = TaylorFeatures.load(tmp_path / "taylor.json")
    assert g.names == f.names and np.array_equal(g.encode(m), f.encode(m))
    with pytest.raises(MotionlangError, match="needs a skeleton"):
        g.decode(f.encode(m))
    assert np.allclose(g.decode(f.encode(m), m.skeleton).joint_angles,
                       f.decode(f.encode(m)).joint_angles)
    assert isinstance(features_from_dict(f.to_dict()), TaylorFeatures)
    with pytest.raises(SkeletonError, match="does not match"):
        f.encode(synthetic_mmm(T=20))

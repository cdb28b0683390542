"""features.root (heading-frame root trajectory)."""
import numpy as np
import pytest

from helpers.mocap import synthetic_mmm, tiny_skeleton, turn
from motionlang.features import root as rootlib
from motionlang.kinematics import Motion


def test_turn_is_rigid():
    m = synthetic_mmm(T=20)
    p, q = m.positions(), turn(m, 1.0, 2.0, -3.0).positions()
    c, s = np.cos(1.0), np.sin(1.0)
    Ry = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    assert np.allclose(q, p @ Ry.T + [2.0, 0, -3.0], atol=1e-9)


def test_increments_integrate_back_and_are_invariant():
    rng = np.random.default_rng(3)
    ground = np.cumsum(rng.normal(size=(30, 2)), 0)
    yaw = np.cumsum(rng.normal(size=30))
    v, dyaw = rootlib.increments(ground, yaw)
    assert v[0].tolist() == [0, 0] and dyaw[0] == 0
    g2, y2 = rootlib.integrate(v, dyaw, (ground[0, 0], ground[0, 1], yaw[0]))
    assert np.allclose(g2, ground) and np.allclose(np.cos(y2 - yaw), 1.0)
    # a body that steps along its own heading has zero sideways motion
    fwd = np.stack([np.sin(yaw[:-1]), np.cos(yaw[:-1])], 1)
    g3 = np.vstack([[0, 0], np.cumsum(0.5 * fwd, 0)])
    v3, _ = rootlib.increments(g3, yaw)
    assert np.allclose(v3[1:, 0], 0) and np.allclose(v3[1:, 1], 0.5)


@pytest.mark.parametrize("make", [synthetic_mmm, None])
def test_root_trajectory_round_trip(make):
    if make is None:
        rng = np.random.default_rng(0)
        sk = tiny_skeleton()
        m = Motion(sk, 30.0, rng.normal(size=(25, 3)), rng.uniform(-1, 1, (25, 3)),
                   rng.uniform(-1, 1, (25, sk.ndof)))
    else:
        m = make(T=50)
    tr = rootlib.root_trajectory(m)
    trans, rot = rootlib.trajectory_to_root(tr, m.skeleton)
    assert np.allclose(m.replace(root_translation=trans, root_rotation=rot).positions(),
                       m.positions(), atol=1e-9)
    # turning the motion changes only the start placement
    tr2 = rootlib.root_trajectory(turn(m, 0.7, 1.0, 2.0))
    for k in ("v", "dyaw", "height", "pitch", "roll"):
        assert np.allclose(tr2[k], tr[k], atol=1e-9), k

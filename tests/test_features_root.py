"""features.root (heading-frame root trajectory) + helpers shared by the feature tests."""
import numpy as np
import pytest

from motionlang.features import root as rootlib
from motionlang.formats.mmm_model import mmm_skeleton
from motionlang.kinematics import Motion
from motionlang.kinematics.rotations import chain, matrix_to_chain
from tests.conftest import tiny_skeleton


def synthetic_mmm(T=201, fps=100.0, seed=0, height=1.75) -> Motion:
    """A smooth MMM motion: the root walks a curve (Z-up source frame), joints swing."""
    sk = mmm_skeleton(height)
    rng = np.random.default_rng(seed)
    t = np.arange(T) / fps
    yaw = 0.3 + 0.4 * t                                       # turning left slowly
    step = 1.2 / fps * np.stack([np.cos(yaw), np.sin(yaw)], 1)  # source x/y ground plane
    xy = np.cumsum(step, 0) + [0.4, -0.7]
    trans = np.column_stack([xy, 0.95 + 0.02 * np.sin(2 * np.pi * 2 * t)])
    rot = np.column_stack([yaw, 0.05 * np.sin(2 * np.pi * t), 0.03 * np.cos(3 * t)])
    phase = rng.uniform(0, 2 * np.pi, sk.ndof)
    amp = rng.uniform(0.05, 0.4, sk.ndof)
    angles = amp * np.sin(2 * np.pi * 1.5 * t[:, None] + phase)
    return Motion(sk, fps, trans, rot, angles, name="synthetic", source_format="mmm",
                  meta={"height": height})


def turn(motion: Motion, theta: float, dx: float, dz: float) -> Motion:
    """The same motion rotated by ``theta`` about the vertical and shifted (dx, 0, dz) on the
    ground, as a rigid motion of the whole body (canonical frame)."""
    sk = motion.skeleton
    W, Ry = sk.world, rootlib.rot_y(theta)
    o = sk.joints[0].offset
    p = (motion.root_translation + o) @ W.T @ Ry.T + [dx, 0.0, dz]
    R = W.T @ Ry @ W @ chain(sk.root_axes, motion.root_rotation)
    return motion.replace(root_translation=p @ W - o,
                          root_rotation=matrix_to_chain(R, sk.root_axes))


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

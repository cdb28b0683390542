"""APE / AVE / CEE / SEE on values worked out by hand."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.metrics.motion import (
    ape,
    ave,
    cee,
    gram,
    position_metrics_mm,
    see,
    temporal_variance,
)


def test_ape_per_joint_hand_values():
    target = np.zeros((2, 2, 3))
    pred = target.copy()
    pred[:, 0] = [3.0, 4.0, 0.0]          # joint 0 is 5 away in both frames
    pred[1, 1] = [0.0, 0.0, 2.0]          # joint 1: 0 then 2 -> mean 1
    np.testing.assert_allclose(ape(pred, target), [5.0, 1.0])
    # a batch (N, T, J, 3) of two copies gives the same means
    np.testing.assert_allclose(ape(np.stack([pred, pred]), np.stack([target, target])),
                               [5.0, 1.0])


def test_ape_weights_sequences_by_frames():
    a_t, b_t = np.zeros((1, 1, 3)), np.zeros((3, 1, 3))
    a_p = a_t + [2.0, 0.0, 0.0]            # 1 frame with error 2, 3 frames with error 0
    np.testing.assert_allclose(ape([a_p, b_t], [a_t, b_t]), [0.5])


def test_ave_hand_values():
    target = np.zeros((3, 1, 3))
    target[:, 0, 1] = [0.0, 0.0, 3.0]      # y: mean 1, unbiased variance (1+1+4)/2 = 3
    target[:, 0, 0] = [0.0, 4.0, 0.0]      # x: mean 4/3, variance (16/9*2 + 64/9)/2 = 16/3
    np.testing.assert_allclose(temporal_variance(target)[0], [16 / 3, 3.0, 0.0])
    pred = np.ones_like(target)            # constant -> zero variance
    np.testing.assert_allclose(ave(pred, target), [np.hypot(16 / 3, 3.0)])
    # AVE ignores a constant offset, APE does not
    np.testing.assert_allclose(ave(target + 7.0, target), [0.0], atol=1e-12)
    assert ape(target + 7.0, target)[0] == pytest.approx(7.0 * np.sqrt(3))


def test_cee_see_hand_values():
    zp = np.array([[3.0, 4.0], [1.0, 1.0]])
    zt = np.array([[0.0, 0.0], [1.0, 1.0]])
    assert cee(zp, zt) == pytest.approx(np.sqrt(12.5) / 2)
    np.testing.assert_allclose(gram([[1.0, 2.0]])[0], [[1.0, 2.0], [2.0, 4.0]])
    # G = [[1,2],[2,4]] vs 0: mean square (1+4+4+16)/4 -> RMS 2.5; the second item is 0
    assert see([[1.0, 2.0], [5.0, 5.0]], [[0.0, 0.0], [5.0, 5.0]]) == pytest.approx(1.25)
    # SEE is blind to a sign flip of the whole embedding (z z^T is the same), CEE is not
    assert see(zp, -zp) == pytest.approx(0.0)
    assert cee(zp, -zp) > 0


def _pose21(rng, T=6):
    """Plausible 21-joint positions facing +Z: left side at +x (the subject's left)."""
    base = np.zeros((21, 3))
    base[:, 1] = np.linspace(0.1, 1.6, 21)
    base[[5, 6, 7, 11, 12, 13, 14, 15], 0] = 0.15    # left shoulder..wrist, hip..toe
    base[[8, 9, 10, 16, 17, 18, 19, 20], 0] = -0.15
    base[0] = [0.0, 0.9, 0.0]
    return base + rng.normal(scale=0.02, size=(T, 21, 3))


def test_position_metrics_mm_root_and_local():
    rng = np.random.default_rng(0)
    target = [_pose21(rng), _pose21(rng, T=4)]
    moved = [t + [0.1, 0.0, 0.0] for t in target]     # shifted 10 cm: local poses unchanged
    m = position_metrics_mm(moved, target)
    assert m["ape_root"] == pytest.approx(100.0)
    assert m["ape_local"] == pytest.approx(0.0, abs=1e-6)
    assert m["ave_root"] == pytest.approx(0.0, abs=1e-6)
    assert m["ape_joints"].shape == (21,)
    # rotating the whole body about the vertical through the root: local frame follows
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    turned = [(t - t[:, :1] * [1, 0, 1]) @ R.T + t[:, :1] * [1, 0, 1] for t in target]
    m = position_metrics_mm(turned, target)
    assert m["ape_local"] == pytest.approx(0.0, abs=1e-6)
    assert m["ape_root"] == pytest.approx(0.0, abs=1e-6)
    assert ape(turned, target)[1:].mean() > 0.01        # but the global positions differ
    # a 5 mm error on one local joint in every frame: that joint's APE is exactly 5 mm
    bent = [t.copy() for t in target]
    for b in bent:
        b[:, 7, 1] += 0.005                               # left wrist up 5 mm
    m = position_metrics_mm(bent, target)
    assert m["ape_joints"][7] == pytest.approx(5.0)
    assert m["ape_local"] == pytest.approx(5.0 / 20)


def test_bad_inputs_raise_motionlang_errors():
    with pytest.raises(MotionlangError):
        ape(np.zeros((2, 3, 3)), np.zeros((3, 3, 3)))
    with pytest.raises(MotionlangError):
        ape([], [])
    with pytest.raises(MotionlangError):
        ave(np.zeros((1, 2, 3)), np.zeros((1, 2, 3)))
    with pytest.raises(MotionlangError):
        cee(np.zeros((2, 3)), np.zeros((2, 4)))

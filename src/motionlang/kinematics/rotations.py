"""Rotation helpers on numpy arrays (float64, radians, right-handed, column vectors).

Conventions: a rotation matrix ``R`` maps vectors of the child frame into the parent frame
(``v_parent = R @ v_child``). A chain of single-axis rotations ``R(a1, t1) @ R(a2, t2) @ ...``
is the intrinsic Euler convention used by BVH, ASF/AMC and MMM alike.
"""
from __future__ import annotations

import numpy as np

AXES = {"x": np.array([1.0, 0.0, 0.0]), "y": np.array([0.0, 1.0, 0.0]),
        "z": np.array([0.0, 0.0, 1.0])}


def axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues' formula for one fixed unit ``axis`` (3,) and angles (...,) -> (..., 3, 3)."""
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    C = 1.0 - c
    out = np.empty(angle.shape + (3, 3))
    out[..., 0, 0] = c + x * x * C
    out[..., 0, 1] = x * y * C - z * s
    out[..., 0, 2] = x * z * C + y * s
    out[..., 1, 0] = y * x * C + z * s
    out[..., 1, 1] = c + y * y * C
    out[..., 1, 2] = y * z * C - x * s
    out[..., 2, 0] = z * x * C - y * s
    out[..., 2, 1] = z * y * C + x * s
    out[..., 2, 2] = c + z * z * C
    return out


def chain(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Product ``R(a_1, t_1) @ ... @ R(a_k, t_k)``; axes (k, 3), angles (..., k) -> (..., 3, 3)."""
    angles = np.asarray(angles, dtype=float)
    axes = np.asarray(axes, dtype=float).reshape(-1, 3)
    if not len(axes):
        return np.broadcast_to(np.eye(3), angles.shape[:-1] + (3, 3)).copy()
    out = axis_angle(axes[0], angles[..., 0])  # not I @ R_1: a (T, 3, 3) product saved
    for i in range(1, len(axes)):
        k = int(np.argmax(np.abs(axes[i])))
        if np.count_nonzero(axes[i]) != 1 or abs(abs(axes[i, k]) - 1.0) > 1e-12:
            out = out @ axis_angle(axes[i], angles[..., i])
            continue
        # a coordinate axis (BVH, ASF): right-multiplying turns two columns in their plane,
        # several times cheaper than a product of (..., 3, 3) stacks
        a, b = (k + 1) % 3, (k + 2) % 3
        t = np.sign(axes[i, k]) * angles[..., i, None]
        c, s = np.cos(t), np.sin(t)
        col_a = out[..., :, a].copy()
        out[..., :, a] = c * col_a + s * out[..., :, b]
        out[..., :, b] = c * out[..., :, b] - s * col_a
    return out


def expmap_to_matrix(r: np.ndarray) -> np.ndarray:
    """Exponential map (..., 3) (axis * angle, radians) -> rotation matrices (..., 3, 3)."""
    r = np.asarray(r, dtype=float)
    theta = np.linalg.norm(r, axis=-1)
    small = theta < 1e-12
    safe = np.where(small, 1.0, theta)
    k = r / safe[..., None]
    K = np.zeros(r.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2] = -k[..., 2], k[..., 1]
    K[..., 1, 0], K[..., 1, 2] = k[..., 2], -k[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -k[..., 1], k[..., 0]
    s, c = np.sin(theta)[..., None, None], np.cos(theta)[..., None, None]
    R = np.eye(3) + s * K + (1 - c) * (K @ K)
    R[small] = np.eye(3)
    return R


def matrix_to_expmap(R: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) -> exponential map (..., 3), angle in [0, pi]."""
    R = np.asarray(R, dtype=float)
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    theta = np.arccos(cos)
    v = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    sin = np.sin(theta)
    out = np.zeros(R.shape[:-2] + (3,))
    regular = sin > 1e-6
    if v.ndim > 1:
        out[regular] = v[regular] * (theta[regular] / (2.0 * sin[regular]))[:, None]
    elif regular:   # one matrix: divide only when sin is not ~0 (no warning at the identity)
        out[...] = v * theta / (2.0 * sin)
    near_pi = (~regular) & (theta > 1.0)
    if np.any(near_pi):
        # sin ~ 0 and theta ~ pi: axis from the largest diagonal entry of (R + I) / 2.
        B = (R[near_pi] + np.eye(3)) / 2.0
        idx = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
        axis = B[np.arange(len(idx)), :, idx]
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        out[near_pi] = axis * theta[near_pi][:, None]
    return out


def matrix_to_chain(R: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Angles of the intrinsic chain ``axes`` (k, 3) that best reproduce ``R`` (..., 3, 3).

    ``axes`` must be coordinate axes (each one of +-x, +-y, +-z), all different, k in 1..3 —
    the DOF layouts that BVH, ASF/AMC and MMM use. For k < 3 the missing axes are appended
    and their (ideally zero) angles dropped. Middle angle in [-pi/2, pi/2] for k = 3;
    every angle keeps its full range for k < 3.
    """
    axes = np.asarray(axes, dtype=float).reshape(-1, 3)
    k = len(axes)
    idx = [int(np.argmax(np.abs(a))) for a in axes]
    sign = [float(np.sign(a[i])) for a, i in zip(axes, idx)]
    if len(set(idx)) != k or any(abs(abs(a[i]) - 1) > 1e-9 for a, i in zip(axes, idx)):
        raise ValueError(f"matrix_to_chain needs distinct coordinate axes, got {axes.tolist()}")
    missing = [i for i in range(3) if i not in idx]
    if k == 2:
        # put the missing axis in the middle so both real angles keep their full range
        full, full_sign, keep = [idx[0], missing[0], idx[1]], [sign[0], 1.0, sign[1]], [0, 2]
    else:
        full, full_sign, keep = idx + missing, sign + [1.0] * (3 - k), list(range(k))
    i, j, l = full
    # parity of the permutation (i, j, l): +1 for cyclic (x,y,z), -1 otherwise
    par = 1.0 if (j - i) % 3 == 1 else -1.0
    R = np.asarray(R, dtype=float)
    # Tait-Bryan intrinsic R = R_i(a) R_j(b) R_l(c) with positive axes.
    b = np.arcsin(np.clip(par * R[..., i, l], -1.0, 1.0))
    a = np.arctan2(-par * R[..., j, l], R[..., l, l])
    c = np.arctan2(-par * R[..., i, j], R[..., i, i])
    out = np.stack([a, b, c], axis=-1) * np.array(full_sign)
    return out[..., keep]


def wrap_angle(x: np.ndarray) -> np.ndarray:
    """Wrap radians into (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(x, dtype=float), 2 * np.pi)

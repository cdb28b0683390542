"""Body geometry of the MMM model and the inverse kinematics that turn foot and pelvis
trajectories into MMM joint angles.

Why IK: the gait and the whole-body primitives are described by where the feet are
(planted footsteps, swing arcs, kicks) and where the pelvis goes. Solving the legs
analytically from those makes stance feet stay exactly where they were planted — no
foot sliding by construction — for every direction, speed and turn.

Source frame throughout: MMM's (Z up, metres, the body faces local +Y, its left is -X).
A yaw ``psi`` (rotation about Z) makes the body face ``(-sin psi, cos psi, 0)``; turning
left increases ``psi``. Left-side arm/leg angles use the left joint's convention; the
right side mirrors them (x-axis DOFs keep their sign, y- and z-axis DOFs flip), as
``Motion.mirror`` does.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motionlang.kinematics.rotations import matrix_to_chain

X, Y, Z = np.eye(3)
SIDES = ("L", "R")


@dataclass(frozen=True)
class Body:
    """Segment lengths (metres) of the MMM model for a subject ``height`` metres tall."""

    height: float

    @property
    def thigh(self) -> float:
        return 0.245 * self.height

    @property
    def shank(self) -> float:
        return 0.246 * self.height

    @property
    def sole(self) -> float:  # ankle joint to sole
        return 0.039 * self.height

    @property
    def hip_dx(self) -> float:  # half hip width
        return 0.052 * self.height

    @property
    def foot_len(self) -> float:  # heel point (under the ankle) to ball of the foot
        return 0.08 * self.height

    @property
    def pelvis_height(self) -> float:
        """Root height when standing with straight legs and flat feet."""
        return self.thigh + self.shank + self.sole

    def hip_offset(self, side: str) -> np.ndarray:
        return np.array([-self.hip_dx if side == "L" else self.hip_dx, 0.0, 0.0])

    def heel_local(self) -> np.ndarray:
        return np.array([0.0, 0.0, -self.sole])

    def ball_local(self) -> np.ndarray:
        return np.array([0.0, self.foot_len, -self.sole])


def smoothstep(x: np.ndarray) -> np.ndarray:
    """Ease-in-out ramp: 0 below 0, 1 above 1, zero slope at both ends."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def heading_vectors(yaw) -> tuple[np.ndarray, np.ndarray]:
    """Forward and left unit vectors (..., 2) on the floor for heading ``yaw`` (rad)."""
    yaw = np.asarray(yaw, dtype=float)
    f = np.stack([-np.sin(yaw), np.cos(yaw)], axis=-1)
    left = np.stack([-np.cos(yaw), -np.sin(yaw)], axis=-1)
    return f, left


def rot(axis: int, a: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations by angles ``a`` about coordinate axis 0 (x), 1 (y) or 2 (z).

    Same result as ``axis_angle(eye(3)[axis], a)``, written out because the generator
    calls it thousands of times per sample.
    """
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def rot_z(a: np.ndarray) -> np.ndarray:
    return rot(2, a)


def foot_rotation(yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """(T, 3, 3) foot frames: yaw about Z, then pitch about the foot's X (toes up > 0)."""
    return rot(2, yaw) @ rot(0, pitch)


def ankle_from_contact(body: Body, point: np.ndarray, yaw: np.ndarray, pitch: np.ndarray,
                       pivot_ball: np.ndarray) -> np.ndarray:
    """(T, 3) ankle positions of a foot whose heel (or ball, where ``pivot_ball``) is at
    ``point`` (T, 3) with the given yaw and pitch (T,) radians."""
    R = foot_rotation(yaw, pitch)
    local = np.where(pivot_ball[:, None], body.ball_local(), body.heel_local())
    return point - np.einsum("tij,tj->ti", R, local)


def pelvis_rotation(angles: np.ndarray) -> np.ndarray:
    """(T, 3, 3) from MMM root angles (T, 3) = (yaw about Z, tilt about Y, pitch about X)."""
    return rot_z(angles[:, 0]) @ rot(1, angles[:, 1]) @ rot(0, angles[:, 2])


def solve_leg(body: Body, side: str, root_pos: np.ndarray, root_rot: np.ndarray,
              ankle: np.ndarray, foot_yaw: np.ndarray, foot_pitch: np.ndarray) -> dict:
    """Analytic leg IK.

    Args:
        root_pos: (T, 3) pelvis (root joint) positions, metres.
        root_rot: (T, 3) root angles (yaw, tilt, pitch), radians.
        ankle: (T, 3) ankle targets; foot_yaw, foot_pitch: (T,) desired foot orientation.

    Returns:
        {dof name: (T,) radians} for the hip (x, z, y), knee and ankle (x, z, y) DOFs of
        ``side``, and ``"reach_error"`` (T,) metres the ankle misses its target by (0 when
        the target is reachable).
    """
    a, b = body.thigh, body.shank
    Rp = pelvis_rotation(root_rot)
    hip = root_pos + Rp @ body.hip_offset(side)
    v = np.einsum("tji,tj->ti", Rp, ankle - hip)  # target in the pelvis frame
    d = np.linalg.norm(v, axis=1)
    d_ok = np.clip(d, abs(a - b) + 1e-3, (a + b) * 0.9999)
    reach_error = np.abs(d - d_ok)
    v = v * (d_ok / np.maximum(d, 1e-9))[:, None]
    kappa = np.arccos(np.clip((d_ok ** 2 - a * a - b * b) / (2 * a * b), -1.0, 1.0))
    uy, uz = -b * np.sin(kappa), -a - b * np.cos(kappa)
    # hip yaw: point the knee where the foot points (relative to the pelvis)
    gamma = np.clip(np.angle(np.exp(1j * (foot_yaw - root_rot[:, 0]))), -0.7, 0.7)
    cg, sg = np.cos(gamma), np.sin(gamma)
    sb = np.clip((v[:, 0] + sg * uy) / (cg * uz), -1.0, 1.0)
    beta = np.arcsin(sb)
    # w = Rz(gamma) Ry(beta) u
    px, pz = sb * uz, np.cos(beta) * uz
    wy, wz = sg * px + cg * uy, pz
    alpha = np.angle(np.exp(1j * (np.arctan2(v[:, 2], v[:, 1]) - np.arctan2(wz, wy))))
    R_leg = Rp @ rot(0, alpha) @ rot(2, gamma) @ rot(1, beta) @ rot(0, -kappa)
    R_ank = np.swapaxes(R_leg, 1, 2) @ foot_rotation(foot_yaw, foot_pitch)
    ank = matrix_to_chain(R_ank, np.stack([X, Z, Y]))
    s = side
    return {f"{s}Hx_joint": alpha, f"{s}Hz_joint": gamma, f"{s}Hy_joint": beta,
            f"{s}Kx_joint": -kappa, f"{s}Ax_joint": ank[:, 0], f"{s}Az_joint": ank[:, 1],
            f"{s}Ay_joint": ank[:, 2], "reach_error": reach_error}


def mirror_sign(dof: str) -> float:
    """Sign that maps a left-side angle to the right side (x keeps, y/z flip)."""
    axis = dof[:-len("_joint")][-1]
    return 1.0 if axis == "x" else -1.0


def side_dof(side: str, name: str) -> str:
    """``side_dof("R", "Sx")`` -> ``"RSx_joint"``."""
    return f"{side}{name}_joint"


#: Relaxed standing arm pose (left-side convention): slightly abducted, elbow a bit bent.
ARM_REST = {"Sx": 0.0, "Sy": 0.12, "Sz": -0.1, "Ex": 0.25, "Ez": 0.0, "Wx": 0.0, "Wy": 0.0}

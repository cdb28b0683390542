"""Root trajectory as heading-frame increments, shared by the angles, positions and Taylor
features.

All quantities are in motionlang's canonical frame (Y up, metres). The heading ``yaw`` is
the rotation about +Y; ``Ry(yaw)`` maps the body's heading frame to the world, so the
heading frame's +z axis points along ``(sin yaw, 0, cos yaw)``.

Increments are taken over the previous frame: ``v_t = Ry(-yaw_{t-1}) (g_t - g_{t-1})`` and
``dyaw_t = wrap(yaw_t - yaw_{t-1})`` for t >= 1, and ``v_0 = 0, dyaw_0 = 0``; integrating
them from the first frame's placement ``(x_0, z_0, yaw_0)`` gives the trajectory back exactly.
"""
from __future__ import annotations

import numpy as np

from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES, chain, matrix_to_chain, wrap_angle

YXZ = np.stack([AXES["y"], AXES["x"], AXES["z"]])


def rot_y(yaw: np.ndarray) -> np.ndarray:
    """yaw (...,) radians -> (..., 3, 3) rotations about +Y."""
    return chain(AXES["y"][None], np.asarray(yaw, dtype=float)[..., None])


def to_heading(v: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """World vectors v (..., 3) -> heading frame, ``Ry(-yaw) v``; yaw broadcasts to (...)."""
    return np.einsum("...ji,...j->...i", rot_y(yaw), v)


def from_heading(v: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Heading-frame vectors v (..., 3) -> world, ``Ry(yaw) v``."""
    return np.einsum("...ij,...j->...i", rot_y(yaw), v)


def increments(ground: np.ndarray, yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ground positions (T, 2) as (x, z) metres and headings (T,) radians ->
    heading-frame steps v (T, 2) as (sideways x, forward z) metres/frame and dyaw (T,)."""
    T = len(yaw)
    v = np.zeros((T, 2))
    dyaw = np.zeros(T)
    if T > 1:
        d = np.zeros((T - 1, 3))
        d[:, 0], d[:, 2] = np.diff(ground[:, 0]), np.diff(ground[:, 1])
        loc = to_heading(d, yaw[:-1])
        v[1:] = loc[:, [0, 2]]
        dyaw[1:] = wrap_angle(np.diff(yaw))
    return v, dyaw


def integrate(v: np.ndarray, dyaw: np.ndarray,
              start: tuple[float, float, float] = (0.0, 0.0, 0.0)
              ) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`increments`: v (T, 2), dyaw (T,), start (x0, z0, yaw0) ->
    ground (T, 2) and yaw (T,). ``v[0]`` and ``dyaw[0]`` are ignored (the start is frame 0)."""
    x0, z0, yaw0 = (float(s) for s in start)
    yaw = yaw0 + np.concatenate([[0.0], np.cumsum(dyaw[1:])])
    d = np.zeros((len(v), 3))
    d[:, 0], d[:, 2] = v[:, 0], v[:, 1]
    world = np.zeros_like(d)
    world[1:] = from_heading(d[1:], yaw[:-1])
    ground = np.stack([x0 + np.cumsum(world[:, 0]), z0 + np.cumsum(world[:, 2])], axis=1)
    return ground, yaw


def root_pose(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """The root's DOFs in the canonical frame.

    Returns:
        p (T, 3) metres: ``world @ root_translation``;
        ypr (T, 3) radians: yaw, pitch, roll with ``Ry(yaw) Rx(pitch) Rz(roll) =
        world @ chain(root_axes, root_rotation) @ world^T`` (conjugating by ``world``
        expresses the root rotation in Y-up axes, so the identity has yaw = pitch = roll = 0).
    """
    sk = motion.skeleton
    W = sk.world
    p = motion.root_translation @ W.T
    Rc = W @ chain(sk.root_axes, motion.root_rotation) @ W.T
    return p, matrix_to_chain(Rc, YXZ)


def root_dofs(p: np.ndarray, ypr: np.ndarray, skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`root_pose`: canonical p (T, 3), ypr (T, 3) -> (root_translation
    (T, 3) in the source frame, root_rotation (T, k) angles of ``skeleton.root_axes``)."""
    W = skeleton.world
    R = W.T @ chain(YXZ, ypr) @ W
    return p @ W, matrix_to_chain(R, skeleton.root_axes)


def root_trajectory(motion: Motion) -> dict[str, np.ndarray]:
    """Taylor-style root description of a motion.

    Returns a dict of arrays: ``v`` (T, 2) heading-frame ground step (sideways, forward)
    metres/frame, ``dyaw`` (T,) radians/frame, ``height`` (T,) metres, ``pitch`` and
    ``roll`` (T,) radians, and ``start`` (3,) = (x0, z0, yaw0) of frame 0.
    """
    p, ypr = root_pose(motion)
    ground = p[:, [0, 2]]
    v, dyaw = increments(ground, ypr[:, 0])
    return {"v": v, "dyaw": dyaw, "height": p[:, 1], "pitch": ypr[:, 1], "roll": ypr[:, 2],
            "start": np.array([ground[0, 0], ground[0, 1], ypr[0, 0]])}


def trajectory_to_root(traj: dict[str, np.ndarray], skeleton,
                       start: tuple[float, float, float] | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`root_trajectory` -> (root_translation (T, 3), root_rotation (T, k)).

    ``start`` (x0, z0, yaw0) places frame 0; default ``traj["start"]`` if present, else the
    origin facing yaw 0.
    """
    if start is None:
        start = traj.get("start", (0.0, 0.0, 0.0))
    ground, yaw = integrate(traj["v"], traj["dyaw"], start)
    p = np.stack([ground[:, 0], traj["height"], ground[:, 1]], axis=1)
    ypr = np.stack([yaw, traj["pitch"], traj["roll"]], axis=1)
    return root_dofs(p, ypr, skeleton)

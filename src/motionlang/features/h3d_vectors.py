"""HumanML3D motion vectors: joint positions <-> the 263 / 251 numbers a frame of the
HumanML3D layout (Guo et al. 2022, ``EricGuo5513/HumanML3D``) stores.

A motion of T frames of J joints gives T-1 rows of ``8 + 9 (J-1) + 3 J`` numbers (263 for
the 22-joint SMPL body at 20 fps, 251 for the 21-joint KIT body at 12.5 fps)::

    [0]      root yaw velocity: -wrap(yaw[t+1] - yaw[t]) / 2 (a half angle, radians)
    [1:3]    root XZ step root[t+1] - root[t], in the heading frame of frame t+1
    [3]      root height
    ric      joints 1..J-1 relative to the root's ground point, in the heading frame of t
    rot      joints 1..J-1: 6D rotations (columns 0 and 1 of the matrix), see below
    vel      all J joints: p[t+1] - p[t] in the heading frame of frame t
    contacts 4 flags, squared step of a foot joint < the body's threshold: left pair, right pair

"Heading frame": ``Ry(-yaw)`` of the world (``features.root``; yaw 0 = facing +Z). Before
that the motion is normalised as the public ``process_file`` does: the lowest joint of all
frames on y = 0, frame 0's root over the origin, frame 0 facing +Z by its hips and shoulders
(``forward = up x ((RH - LH) + (RS - LS))``). :func:`vectors_to_joints` is the public
``recover_from_ric``: integrate the yaw velocity and root steps, turn the ``ric`` positions
back; it does not use the rotations.

What matches the public code, given the same joint positions: the layout, the normalisation,
the per-frame heading (``heading="public"``: its inverse kinematics' forward vector, which
takes the hips with the opposite sign of the shoulders, as ``common/skeleton.py`` unpacks its
``face_joint_idx``, smoothed by a Gaussian of 20 frames), the foot thresholds (0.002 m^2
per frame for SMPL; 0.05 in the KIT files' millimetres) and the rotation channels (its
swing-only IK from the fixed ``raw_offsets`` directions; a chain that starts at the neck is
relative to the root heading, not to the spine, as in the public code). As there, the
smoothed heading of frame 0 is in general a few degrees off +Z; the recovered joints (and
``new_joints``) are the normalised joints turned by it: the input moved rigidly, exactly
(``joints_to_vectors`` returns them as ``layout_joints``). Where it differs:

* the public code first re-targets every motion to one reference subject's bone lengths
  (``uniform_skeleton``); here each motion keeps its own;
* the yaw velocity is exact where the heading crosses +-180 degrees; the public
  ``arcsin`` of a quaternion component flips its sign on those frames;
* a bone of zero length gets the identity rotation (NaN in the public code);
* arithmetic in float64, rows stored as float32 (the public code works in float32);
* KIT sides: the public KIT settings call joints 11-15 / 5-7 the right side
  (``face_joint_indx = [11, 16, 5, 8]``); the MMM names of those joints, used here
  (``features.joint_map``), say left. Here the anatomical sides are used, so KIT exports
  face +Z and contacts are (left mid-foot, left toe, right mid-foot, right toe).

``heading="body"`` uses the hips-and-shoulders heading of each frame, unsmoothed
(``features.positions.facing_yaw``): the channels then follow the pelvis and chest at once.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_MIRROR, KIT21_NAMES
from motionlang.features.rig_maps import SMPL_JOINT_NAMES
from motionlang.features.root import from_heading, rot_y, to_heading
from motionlang.kinematics.rotations import wrap_angle

HEADINGS = ("public", "body")
#: the public code's smoothing of the forward direction (frames, at any frame rate)
HEADING_SIGMA = 20.0


@dataclass(frozen=True)
class H3DBody:
    """One body of the layout.

    Attributes:
        name: ``"smpl"`` or ``"kit"``. joint_names: J names, in array order.
        chains: the public kinematic chains (each starts at a joint already placed).
        raw_offsets: (J, 3) unit rest direction of each joint's bone (the IK's reference).
        face: right hip, left hip, right shoulder, left shoulder (anatomical sides).
        feet: the 4 contact joints: left pair, then right pair.
        fps: frame rate. unit: metres per unit of the files (0.001: millimetres).
        contact_threshold: squared foot step per frame, in file units, below which a foot
            is in contact.
        mirror: left/right partner of each joint.
    """

    name: str
    joint_names: tuple[str, ...]
    chains: tuple[tuple[int, ...], ...]
    raw_offsets: tuple[tuple[int, int, int], ...]
    face: tuple[int, int, int, int]
    feet: tuple[int, int, int, int]
    fps: float
    unit: float
    contact_threshold: float
    mirror: tuple[int, ...]

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    @property
    def parents(self) -> tuple[int, ...]:
        parents = [-1] * self.n_joints
        for chain in self.chains:
            for a, b in zip(chain[:-1], chain[1:]):
                parents[b] = a
        return tuple(parents)

    @property
    def dim(self) -> int:
        return vector_dim(self.n_joints)


def _sides(names: tuple[str, ...]) -> tuple[int, ...]:
    swap = {"left": "right", "right": "left"}
    return tuple(names.index("_".join([swap.get(n.split("_")[0], n.split("_")[0])]
                                      + n.split("_")[1:])) for n in names)


X, NX, Y, NY, Z = (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)
SMPL_H3D = H3DBody(
    "smpl", SMPL_JOINT_NAMES,
    chains=((0, 2, 5, 8, 11), (0, 1, 4, 7, 10), (0, 3, 6, 9, 12, 15), (9, 14, 17, 19, 21),
            (9, 13, 16, 18, 20)),
    raw_offsets=((0, 0, 0), X, NX, Y, NY, NY, Y, NY, NY, Y, Z, Z, Y, X, NX, Z, NY, NY, NY, NY,
                 NY, NY),
    face=(2, 1, 17, 16), feet=(7, 10, 8, 11), fps=20.0, unit=1.0, contact_threshold=0.002,
    mirror=_sides(SMPL_JOINT_NAMES))
KIT_H3D = H3DBody(
    "kit", KIT21_NAMES,
    chains=((0, 11, 12, 13, 14, 15), (0, 16, 17, 18, 19, 20), (0, 1, 2, 3, 4), (3, 5, 6, 7),
            (3, 8, 9, 10)),
    raw_offsets=((0, 0, 0), Y, Y, Y, Y, X, NY, NY, NX, NY, NY, X, NY, NY, Z, Z, NX, NY, NY, Z,
                 Z),
    face=(16, 11, 8, 5), feet=(14, 15, 19, 20), fps=12.5, unit=0.001, contact_threshold=0.05,
    mirror=KIT21_MIRROR)
H3D_BODIES = {"smpl": SMPL_H3D, "kit": KIT_H3D}


def vector_dim(n_joints: int) -> int:
    """Numbers per row for J joints: 4 + 3 (J-1) + 6 (J-1) + 3 J + 4."""
    return 8 + 9 * (n_joints - 1) + 3 * n_joints


def rows_layout(body: H3DBody) -> dict:
    """What a model that reads this body's rows records of them (in its checkpoint): layout
    name, body, frame rate (Hz), unit (metres per file unit) and row size."""
    return {"layout": "h3d_vectors", "body": body.name, "fps": float(body.fps),
            "unit": float(body.unit), "dim": body.dim}


def layout_for_dim(dim: int) -> dict | None:
    """:func:`rows_layout` of the body whose rows have ``dim`` numbers; None for any other
    size (rows of some other features)."""
    return next((rows_layout(b) for b in H3D_BODIES.values() if b.dim == dim), None)


def vector_slices(n_joints: int) -> dict[str, slice]:
    """Name -> columns of each part of a row (see the module docstring)."""
    J, out, start = n_joints, {}, 0
    for name, size in (("root_yaw_velocity", 1), ("root_velocity_xz", 2), ("root_height", 1),
                       ("ric", 3 * (J - 1)), ("rotations", 6 * (J - 1)),
                       ("velocities", 3 * J), ("contacts", 4)):
        out[name] = slice(start, start + size)
        start += size
    return out


def _check(positions, body: H3DBody, least: int = 2) -> np.ndarray:
    p = np.array(positions, dtype=float)
    if p.ndim != 3 or p.shape[1:] != (body.n_joints, 3) or len(p) < least:
        raise MotionlangError(f"{body.name} joints must be (T, {body.n_joints}, 3) with "
                              f"T >= {least}, got {p.shape}")
    if not np.isfinite(p).all():
        raise MotionlangError("joint positions: non-finite values")
    return p


def heading_yaw(positions, body: H3DBody, heading: str = "public") -> np.ndarray:
    """(T, J, 3) -> (T,) heading yaw, radians (0 = facing +Z): ``"public"`` as the public
    IK computes it (hips and shoulders with opposite signs, smoothed over 20 frames),
    ``"body"`` from ``(RH - LH) + (RS - LS)`` per frame."""
    if heading not in HEADINGS:
        raise MotionlangError(f"heading must be one of {HEADINGS}, got {heading!r}")
    p = np.asarray(positions, dtype=float)
    rh, lh, rs, ls = body.face
    hips = p[:, rh] - p[:, lh]
    across = (-hips if heading == "public" else hips) + p[:, rs] - p[:, ls]
    across = across / np.maximum(np.linalg.norm(across, axis=-1, keepdims=True), 1e-12)
    forward = np.stack([across[:, 2], np.zeros(len(p)), -across[:, 0]], axis=1)
    if heading == "public":
        forward = gaussian_filter1d(forward, HEADING_SIGMA, axis=0, mode="nearest")
    return np.arctan2(forward[:, 0], forward[:, 2])


def normalise(positions, body: H3DBody) -> np.ndarray:
    """The public normalisation: lowest joint of all frames on y = 0, frame 0's root over
    the origin, frame 0 facing +Z by ``(RH - LH) + (RS - LS)``."""
    p = _check(positions, body, least=1)
    p[..., 1] -= p[..., 1].min()
    p[..., 0] -= p[0, 0, 0]
    p[..., 2] -= p[0, 0, 2]
    return to_heading(p, heading_yaw(p[:1], body, "body")[0])


def _between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Smallest rotations taking unit vectors u (..., 3) onto the directions v (..., 3)
    (broadcast) -> (..., 3, 3); identity where v has no length, half a turn where v
    opposes u."""
    u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    v = np.where(n > 1e-12, v / np.maximum(n, 1e-12), u)
    w, c = np.cross(u, v), np.sum(u * v, axis=-1)
    K = np.zeros(v.shape + (3,))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    R = np.eye(3) + K + (K @ K) / np.maximum(1.0 + c, 1e-12)[..., None, None]
    flip = c < -1.0 + 1e-9
    if flip.any():
        uf = u[flip]
        a = np.cross(uf, np.where(np.abs(uf[:, :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]))
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        R[flip] = 2.0 * a[:, :, None] * a[:, None, :] - np.eye(3)
    return R


def rotation_channels(positions, yaw, body: H3DBody) -> np.ndarray:
    """(T, J, 3), heading yaw (T,) -> (T, 6 (J-1)): per joint 1..J-1, columns 0 and 1 of its
    rotation relative to the previous joint of its chain (the first: to ``Ry(-yaw)``), the
    smallest one that turns its ``raw_offsets`` direction onto its bone."""
    p = np.asarray(positions, dtype=float)
    parents = np.array(body.parents[1:])
    G = _between(np.array(body.raw_offsets[1:], dtype=float), p[:, 1:] - p[:, parents])
    base = G[:, np.maximum(parents - 1, 0)]                       # previous joint's G
    starts = np.isin(np.arange(1, body.n_joints), [c[1] for c in body.chains])
    base[:, starts] = rot_y(-np.asarray(yaw, dtype=float))[:, None]
    local = np.swapaxes(base, -1, -2) @ G                         # (T, J-1, 3, 3)
    return np.concatenate([local[..., 0], local[..., 1]], axis=-1).reshape(len(p), -1)


def joints_to_vectors(positions, body: H3DBody, heading: str = "public"
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions (T >= 2, J, 3) in the body's file unit, Y up -> (vectors (T-1, D),
    layout joints (T, J, 3)): the input moved rigidly so that the vectors describe it, i.e.
    ``vectors_to_joints(vectors) == layout_joints[:-1]`` within float rounding."""
    p = normalise(_check(positions, body), body)
    yaw = heading_yaw(p, body, heading)
    root = p[:, 0]
    ground = root * np.array([1.0, 0.0, 1.0])
    ric = to_heading(p[:, 1:] - ground[:, None], yaw[:, None])
    step = to_heading(root[1:] - root[:-1], yaw[1:])[:, [0, 2]]
    vel = to_heading(p[1:] - p[:-1], yaw[:-1, None])
    feet = np.sum((p[1:, list(body.feet)] - p[:-1, list(body.feet)]) ** 2, axis=-1)
    n = len(p) - 1
    vectors = np.concatenate([
        -wrap_angle(np.diff(yaw))[:, None] / 2.0, step, root[:-1, 1:2],
        ric[:-1].reshape(n, -1), rotation_channels(p[:-1], yaw[:-1], body),
        vel.reshape(n, -1), (feet < body.contact_threshold).astype(float)], axis=1)
    return vectors, to_heading(p, yaw[0])


def vectors_to_joints(vectors, body: H3DBody) -> np.ndarray:
    """(N, D) rows -> (N, J, 3) joint positions (the public ``recover_from_ric``): frame 0's
    root over the origin, its heading facing +Z; rotation channels unused."""
    v = np.asarray(vectors, dtype=float)
    J = body.n_joints
    if v.ndim != 2 or v.shape[1] != body.dim or not len(v):
        raise MotionlangError(f"{body.name} vectors must be (N >= 1, {body.dim}), got "
                              f"{v.shape}")
    yaw = -2.0 * np.concatenate([[0.0], np.cumsum(v[:-1, 0])])
    step = np.zeros((len(v), 3))
    step[1:, [0, 2]] = v[:-1, 1:3]
    root = np.cumsum(from_heading(step, yaw), axis=0)
    root[:, 1] = v[:, 3]
    ric = v[:, vector_slices(J)["ric"]].reshape(len(v), J - 1, 3)
    joints = from_heading(ric, yaw[:, None]) + root[:, None] * np.array([1.0, 0.0, 1.0])
    return np.concatenate([root[:, None], joints], axis=1)


def mirror_joints(positions, body: H3DBody) -> np.ndarray:
    """(T, J, 3) -> the mirror image: x negated, left and right joints exchanged."""
    p = np.asarray(positions, dtype=float)
    return p[:, list(body.mirror)] * np.array([-1.0, 1.0, 1.0])


def group_std(std, n_joints: int) -> np.ndarray:
    """Per-column standard deviations -> the public ``Std.npy``: each part of the row (yaw
    velocity, XZ step, height, ric, rotations, velocities, contacts) gets its mean; a part
    whose mean is 0 (constant everywhere) gets 1 so that normalising never divides by 0."""
    s = np.array(std, dtype=float)
    for sl in vector_slices(n_joints).values():
        m = s[sl].mean()
        s[sl] = m if m > 0 else 1.0
    return s

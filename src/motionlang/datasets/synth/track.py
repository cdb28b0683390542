"""Segments of a synthetic motion before inverse kinematics, and their assembly into a
:class:`Motion` on the MMM skeleton.

A :class:`Track` holds per-frame targets: pelvis (root) position and angles, each foot's
ankle position and orientation, which foot is on the ground, and the upper-body DOFs
(spine, neck, arms) directly as angles. Segments are built one after another, each
starting from the :class:`Stance` the previous one ended in, and concatenated.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import distance_transform_edt, gaussian_filter1d, minimum_filter1d

from motionlang.datasets.synth.body import (
    ARM_REST,
    SIDES,
    Body,
    ankle_from_contact,
    pelvis_rotation,
    smoothstep,
    solve_leg,
)
from motionlang.formats.mmm_model import MMM_DOF_ORDER, mmm_kinematics

FPS = 100.0
#: Upper-body DOFs the primitives drive directly (everything but legs and feet).
UPPER_DOFS = tuple(f"{s}{j}_joint" for s in ("BP", "BT", "BLN", "BUN") for j in "xyz") + tuple(
    f"{side}{k}_joint" for side in SIDES for k in ARM_REST)


@dataclass
class Stance:
    """Standing state between segments: feet planted flat, pelvis above their middle.

    Attributes:
        feet: {"L"/"R": (x, y, yaw)} heel point on the floor (metres) and foot yaw (rad).
        yaw: body heading (rad); the body faces ``(-sin yaw, cos yaw)``.
    """

    feet: dict[str, tuple[float, float, float]]
    yaw: float

    @property
    def center(self) -> np.ndarray:
        return (np.array(self.feet["L"][:2]) + np.array(self.feet["R"][:2])) / 2

    @classmethod
    def standing(cls, center, yaw: float, width: float, toe_out: float = 0.05) -> Stance:
        c = np.asarray(center, dtype=float)
        left = np.array([-np.cos(yaw), -np.sin(yaw)])
        return cls({"L": (*(c + left * width / 2), yaw + toe_out),
                    "R": (*(c - left * width / 2), yaw - toe_out)}, float(yaw))


@dataclass
class Track:
    """Per-frame targets of one segment (T frames at :data:`FPS`).

    Attributes:
        root_pos: (T, 3) pelvis position, metres (MMM source frame, Z up).
        root_rot: (T, 3) pelvis (yaw, tilt about Y, pitch about X), radians.
        ankle: {side: (T, 3)} ankle targets; foot_yaw / foot_pitch: {side: (T,)} radians.
        contact: {side: (T,) bool} foot on the ground (ground truth for the tests).
        upper: {dof: (T,)} radians for every name in :data:`UPPER_DOFS`.
    """

    root_pos: np.ndarray
    root_rot: np.ndarray
    ankle: dict[str, np.ndarray]
    foot_yaw: dict[str, np.ndarray]
    foot_pitch: dict[str, np.ndarray]
    contact: dict[str, np.ndarray]
    upper: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return len(self.root_pos)


def rest_upper(T: int, style: dict) -> dict[str, np.ndarray]:
    """Relaxed standing upper body with the sample's posture offsets (``style["posture"]``)."""
    out = {n: np.zeros(T) for n in UPPER_DOFS}
    for side in SIDES:
        for k, v in ARM_REST.items():
            sign = 1.0 if (side == "L" or k[-1] == "x") else -1.0
            out[f"{side}{k}_joint"][:] = sign * v
    for name, v in style.get("posture", {}).items():
        out[name] = out[name] + v
    return out


def standing_track(body: Body, stance: Stance, T: int, style: dict,
                   drop: float = 0.004) -> Track:
    """T frames of quiet standing in ``stance``."""
    c = stance.center
    root_pos = np.tile([c[0], c[1], body.pelvis_height - drop * body.height / 1.75], (T, 1))
    root_rot = np.zeros((T, 3))
    root_rot[:, 0] = stance.yaw
    ankle, fyaw, fpitch, contact = {}, {}, {}, {}
    for s in SIDES:
        x, y, yaw = stance.feet[s]
        fyaw[s] = np.full(T, yaw)
        fpitch[s] = np.zeros(T)
        ankle[s] = ankle_from_contact(body, np.tile([x, y, 0.0], (T, 1)), fyaw[s], fpitch[s],
                                      np.zeros(T, bool))
        contact[s] = np.ones(T, bool)
    return Track(root_pos, root_rot, ankle, fyaw, fpitch, contact, rest_upper(T, style))


def concat_tracks(tracks: list[Track]) -> Track:
    cat = np.concatenate
    return Track(cat([t.root_pos for t in tracks]), cat([t.root_rot for t in tracks]),
                 {s: cat([t.ankle[s] for t in tracks]) for s in SIDES},
                 {s: cat([t.foot_yaw[s] for t in tracks]) for s in SIDES},
                 {s: cat([t.foot_pitch[s] for t in tracks]) for s in SIDES},
                 {s: cat([t.contact[s] for t in tracks]) for s in SIDES},
                 {n: cat([t.upper[n] for t in tracks]) for n in UPPER_DOFS})


def limit_reach(body: Body, track: Track, margin: float = 0.995) -> None:
    """Lower the pelvis where a planted leg could not reach its ankle target (in place).

    The allowed height is min-filtered and smoothed so the pelvis dips smoothly, then
    clamped again so that no frame stays out of reach.
    """
    L = (body.thigh + body.shank) * margin
    Rp = pelvis_rotation(track.root_rot)
    zmax = np.full(track.n_frames, np.inf)
    for s in SIDES:
        hip_rel = Rp @ body.hip_offset(s)
        hip_xy = track.root_pos[:, :2] + hip_rel[:, :2]
        dxy2 = np.sum((track.ankle[s][:, :2] - hip_xy) ** 2, axis=1)
        hz = track.ankle[s][:, 2] + np.sqrt(np.maximum(L * L - dxy2, 0.0))
        hz[~track.contact[s]] = np.inf  # a swinging foot may fall short of its target
        zmax = np.minimum(zmax, hz - hip_rel[:, 2])
    z = track.root_pos[:, 2]
    if np.all(z <= zmax):
        return
    target = np.minimum(z, zmax)
    smooth = gaussian_filter1d(minimum_filter1d(target, 15, mode="nearest"), 4, mode="nearest")
    track.root_pos[:, 2] = np.minimum(smooth, zmax)


@functools.lru_cache(maxsize=1)
def dof_limits() -> dict[str, tuple[float, float]]:
    """MMM joint limits (radians) of the 44 recorded DOFs."""

    names = set(MMM_DOF_ORDER)
    return {n["name"]: tuple(n["limits"]) for n in mmm_kinematics()["nodes"]
            if n["name"] in names and "limits" in n}


def solve_track(body: Body, track: Track, dof_names: list[str]) -> np.ndarray:
    """(T, D) joint angles in ``dof_names`` order: legs by IK, the rest from ``upper``.

    Upper-body DOFs are clipped to the MMM joint limits; so are the ankles of a foot in the
    air (a planted foot keeps the angle that holds it flat on the floor).
    """
    T = track.n_frames
    col = {n: i for i, n in enumerate(dof_names)}
    lim = dof_limits()
    out = np.zeros((T, len(dof_names)))
    for n, v in track.upper.items():
        lo, hi = lim.get(n, (-np.inf, np.inf))
        out[:, col[n]] = np.clip(v, lo, hi)
    for s in SIDES:
        sol = solve_leg(body, s, track.root_pos, track.root_rot, track.ankle[s],
                        track.foot_yaw[s], track.foot_pitch[s])
        sol.pop("reach_error")
        air = ~track.contact[s]
        # A swinging foot's target can fall out of reach for a few frames, where the IK
        # straightens the knee abruptly; in the air the exact foot position does not
        # matter, so low-pass the leg there, fading to the exact solution at contacts.
        w = smoothstep(distance_transform_edt(air) / 8.0) if air.any() else np.zeros(T)
        for n, v in sol.items():
            v = v + w * (gaussian_filter1d(v, 3.0, mode="nearest") - v)
            if n[1] == "A" and n in lim:
                v = np.where(air, np.clip(v, *lim[n]), v)
            out[:, col[n]] = v
    return out

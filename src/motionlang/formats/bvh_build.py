"""The second half of reading a BVH: parsed nodes and channel values -> a ``Motion``.

Position channels: on the root they add to its OFFSET (the original Biovision rule); on
any other joint they replace the OFFSET components they name (what exporters mean: their
values equal the bone, up to float noise). Constant ones simply become the offset; animated
ones either carry the root motion (re-rooting, below) or are averaged into the offset, with
their largest deviation recorded in ``meta["bvh_position_spread_m"]``.

Re-rooting: when a joint further down the single chain that starts at the root has
animated position channels (Bandai Namco: ``joint_Root`` on the floor, ``Hips`` animated
below it), that joint becomes the Motion's root and the chain above it is dropped: per
frame its world translation and rotation are composed from the ancestors' offsets,
position channels and rotations (the deepest such joint: see ``_choose_root``).
``meta["bvh_hierarchy"]`` keeps everything a writer needs to restore the file's layout.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.formats.units import (
    BVH_UNITS,
    SCALED_STATURE_M,
    detect_unit,
    estimate_stature,
    sample_frames,
)
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES, chain, matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton

MAX_ABS = 1e12  # largest magnitude accepted for any number; FK would overflow beyond
CHANNELS = {f"{c}{kind}": (c.lower(), kind) for c in "XYZ" for kind in ("position", "rotation")}
CONSTANT_TOL = 1e-5  # position channels spreading less than this (relative) are constant
ANGLE_TOL = 1e-6     # degrees: rotation channels of dropped ancestors spreading less are constant


def _joint_names(path: Path, nodes: list[dict]) -> list[str]:
    """Unique skeleton names: End Sites colliding with a joint get a number appended."""
    out, seen = [], set()
    for n in nodes:
        name, k = n["name"], 2
        if name in seen and not n["end"]:
            raise MotionFormatError(path, f"duplicate joint name {name!r}", line=n["line"])
        while name in seen:
            name, k = f"{n['name']}{k}", k + 1
        seen.add(name)
        out.append(name)
    return out


class _Channels:
    """Where each node's channels are: ``pos[i]`` {axis: column}, ``rot[i]`` [(axis, column)]."""

    def __init__(self, nodes: list[dict]):
        self.pos: list[dict[str, int]] = []
        self.rot: list[list[tuple[str, int]]] = []
        col = 0
        for n in nodes:
            p, r = {}, []
            for c in n["channels"]:
                axis, kind = CHANNELS[c]
                if kind == "position":
                    p[axis] = col
                else:
                    r.append((axis, col))
                col += 1
            self.pos.append(p)
            self.rot.append(r)

    def axes(self, i: int) -> np.ndarray:
        """(k, 3) rotation axes of node i in channel order."""
        return np.array([AXES[a] for a, _ in self.rot[i]]).reshape(-1, 3)

    def angles(self, i: int, data: np.ndarray) -> np.ndarray:
        """(T, k) radians of node i's rotation channels."""
        out = data[:, [c for _, c in self.rot[i]]]
        return np.deg2rad(out, out=out)

    def local_translation(self, i: int, offset: np.ndarray, data: np.ndarray) -> np.ndarray:
        """(T, 3) file units: node i's translation from its parent (OFFSET and channels)."""
        out = np.repeat(offset[None], len(data), axis=0)
        for axis, c in self.pos[i].items():
            k = "xyz".index(axis)
            out[:, k] = data[:, c] + (out[:, k] if i == 0 else 0.0)
        return out


def _position_offsets(nodes, ch: _Channels, data: np.ndarray):
    """Offsets implied by position channels (file units), which nodes' channels are
    animated, and their largest deviation from the mean (file units)."""
    bones = [np.linalg.norm(n["offset"]) for n in nodes[1:]]
    scale = float(np.median([b for b in bones if b > 0])) if any(b > 0 for b in bones) else 1.0
    offsets, animated, spread = [n["offset"].copy() for n in nodes], set(), {}
    for i, _n in enumerate(nodes):
        if not ch.pos[i]:
            continue
        axes, cols = zip(*ch.pos[i].items())
        v = data[:, list(cols)]
        mean = v.mean(axis=0)
        dev = float(np.linalg.norm(v - mean, axis=1).max())
        if i > 0:  # the root's channels add to its OFFSET instead
            for a, m in zip(axes, mean):
                offsets[i]["xyz".index(a)] = m
        if dev > CONSTANT_TOL * max(float(np.linalg.norm(offsets[i])), scale):
            animated.add(i)
            spread[i] = dev
    return offsets, animated, spread, scale


def _choose_root(nodes, kids, ch: _Channels, data: np.ndarray, animated: set[int]) -> int:
    """Index of the node to root the Motion at: the deepest node with animated position
    channels on the single chain that starts at the file's root (each node of it but the
    last having one child), provided it can carry the composed transform (3 position
    channels, and 3 rotation channels unless its ancestors never rotate); else 0.

    The deepest, not the topmost: Bandai Namco's ``joint_Root`` sometimes jumps forward
    while ``Hips`` jumps back (dash, run), and ``Hips`` is the body either way."""
    line = [0]
    while len(kids[line[-1]]) == 1 and not nodes[kids[line[-1]][0]]["end"]:
        line.append(kids[line[-1]][0])
    for i in reversed(line[1:]):
        if i in animated:
            still = not any(np.any(data[:, c] != 0) for a in range(i) for _, c in ch.rot[a])
            if len(ch.pos[i]) == 3 and (len(ch.rot[i]) == 3 or still):
                return i
    return 0


def _compose_root(nodes, ch: _Channels, data: np.ndarray, r: int):
    """World translation (T, 3) file units, rotation axes (k, 3) and angles (T, k) radians
    of node ``r`` through its dropped ancestors ``0..r-1``."""
    t, R = np.zeros((len(data), 3)), None
    for a in range(r + 1):
        L = ch.local_translation(a, nodes[a]["offset"], data)
        t += L if R is None else np.einsum("tij,tj->ti", R, L)
        if a < r and ch.rot[a] and any(np.any(data[:, c] != 0) for _, c in ch.rot[a]):
            Q = chain(ch.axes(a), ch.angles(a, data))
            R = Q if R is None else R @ Q
    axes, own = ch.axes(r), ch.angles(r, data)
    if R is None:  # the ancestors never rotate: the file's own angles, untouched
        return t, axes, own
    return t, axes, np.unwrap(matrix_to_chain(R @ chain(axes, own), axes), axis=0)


def _dropped_values(node: dict, i: int, ch: _Channels, data: np.ndarray, scale: float) -> list:
    """Channel values (file units, degrees) a writer re-emits for a dropped ancestor: the
    file's own when constant, else neutral ones (the new root absorbs the difference)."""
    out = []
    for c in node["channels"]:
        axis, kind = CHANNELS[c]
        v = data[:, ch.pos[i][axis] if kind == "position" else dict(ch.rot[i])[axis]]
        mean = float(v.mean())
        tol = ANGLE_TOL if kind == "rotation" else CONSTANT_TOL * max(abs(mean), scale)
        if np.ptp(v) <= tol:
            out.append(mean)
        else:
            out.append(0.0 if kind == "rotation" or i == 0 else
                       float(node["offset"]["xyz".index(axis)]))
    return out


class _Rooted:
    """The parsed file rooted at ``nodes[r]`` (``_choose_root``): offsets, root motion and
    joint angles in file units and radians, ready to become a Motion at any unit."""

    def __init__(self, path: Path, nodes: list[dict], data: np.ndarray, fps: float):
        self.path, self.nodes, self.fps = path, nodes, fps
        self.names = _joint_names(path, nodes)
        kids: list[list[int]] = [[] for _ in nodes]
        for i, n in enumerate(nodes[1:], start=1):
            kids[n["parent"]].append(i)
        self.ch = ch = _Channels(nodes)
        self.offsets, animated, self.spread, self.scale = _position_offsets(nodes, ch, data)
        self.r = r = _choose_root(nodes, kids, ch, data, animated)
        if r > 0:
            self.trans, self.root_axes, self.root_rot = _compose_root(nodes, ch, data, r)
            self.offsets[r] = np.zeros(3)
        else:
            self.trans = np.zeros((len(data), 3))
            for axis, c in ch.pos[0].items():
                self.trans[:, "xyz".index(axis)] = data[:, c]
            self.root_axes, self.root_rot = ch.axes(0), ch.angles(0, data)
        angle_cols = [c for i in range(r + 1, len(nodes)) for _, c in ch.rot[i]]
        self.angles = data[:, angle_cols]  # a copy: converted in place, no third (T, D) array
        np.deg2rad(self.angles, out=self.angles)

    def skeleton(self, u: float) -> Skeleton:
        """The skeleton of nodes ``r..``, ``u`` metres per file unit."""
        nodes, names, r = self.nodes, self.names, self.r
        index = {i: i - r for i in range(r, len(nodes))}  # dropped ancestors are nodes 0..r-1
        joints = [Joint(names[i], -1 if i == r else index[nodes[i]["parent"]],
                        self.offsets[i] * u,
                        axes=np.zeros((0, 3)) if i == r else self.ch.axes(i),
                        dof_names=() if i == r else tuple(f"{names[i]}_{c}"
                                                           for c in nodes[i]["channels"]
                                                           if c.endswith("rotation")))
                  for i in range(r, len(nodes))]
        try:
            return Skeleton(joints, world=np.eye(3), root_axes=self.root_axes, file_unit=u,
                            name=f"bvh:{self.path.stem}")
        except SkeletonError as exc:
            raise MotionFormatError(self.path, str(exc)) from None

    def motion(self, u: float, rows, meta=None) -> Motion:
        """The Motion of frames ``rows``, ``u`` metres per file unit."""
        try:
            return Motion(self.skeleton(u), self.fps, self.trans[rows] * u, self.root_rot[rows],
                          self.angles[rows], name=self.path.stem, source_format="bvh",
                          meta=meta or {})
        except MotionFormatError as exc:
            raise MotionFormatError(self.path, exc.reason, frame=exc.frame) from None


def build_motion(path: Path, nodes: list[dict], data: np.ndarray, fps: float,
                 given: tuple[str, float] | None) -> Motion:
    """A Motion from the parsed ``nodes`` (see ``bvh_read._parse_hierarchy``) and the
    channel values ``data`` (T, C) in file units and degrees.

    Args:
        given: (unit name, metres per file unit) chosen by the caller, or None to decide
            the unit from the body.
    """
    body = _Rooted(path, nodes, data, fps)
    r, names = body.r, body.names
    sample = body.motion(1.0, sample_frames(len(data)))
    stature = estimate_stature(sample.positions(), sample.skeleton.parents)
    meta: dict = {"path": str(path)}
    u = _choose_unit(meta, given, stature)
    meta["stature_m"] = stature * u
    meta["bvh_root_channels"] = list(nodes[r]["channels"])
    meta["bvh_hierarchy"] = _hierarchy_meta(body, data, u)
    meta["bvh_position_spread_m"] = {names[i]: d * u for i, d in body.spread.items() if i > r}
    return body.motion(u, slice(None), meta)


def _choose_unit(meta: dict, given: tuple[str, float] | None, stature: float) -> float:
    """Metres per file unit: the caller's, else the one that makes the body human-sized;
    records ``unit`` (and ``unit_note``) in ``meta``."""
    if given is not None:
        (meta["unit"], u), meta["unit_note"] = given, "given by the caller"
    else:
        meta["unit"], u = detect_unit(stature)
        if meta["unit"] == BVH_UNITS:
            meta["unit_note"] = (
                f"no length unit makes the body human-sized (it measures {stature:.4g} "
                f"file units); scaled so that it is {SCALED_STATURE_M} m tall" if stature > 0
                else "the body has no size; 1 file unit taken as 1 m")
    return u


def _hierarchy_meta(body: _Rooted, data: np.ndarray, u: float) -> dict:
    """``meta["bvh_hierarchy"]``: every node of the file as a writer needs it to restore
    the layout, the dropped ancestors with the channel values to re-emit."""
    r, names = body.r, body.names
    return {
        "file_unit": u,
        "dropped": [body.nodes[a]["name"] for a in range(r)],
        "nodes": [{"name": n["site_name"] if n["end"] else n["name"],
                   "joint": names[i] if i >= r else None, "parent": n["parent"],
                   "offset": [float(v) for v in n["offset"]], "channels": list(n["channels"]),
                   "end_site": n["end"],
                   **({"values": _dropped_values(n, i, body.ch, data, body.scale)}
                      if i < r else {})}
                  for i, n in enumerate(body.nodes)]}

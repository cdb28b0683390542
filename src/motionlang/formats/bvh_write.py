"""Writing BVH: a Motion read from a BVH file (or one made on that rig, e.g. retargeted
onto it) goes back in the file's own layout; any other Motion in a plain one.

The file's own layout (``meta["bvh_hierarchy"]``, see :mod:`motionlang.formats.bvh`): the
dropped ancestors of a re-rooted Motion come back with their own constant channel values
and the new root's channels carry what is left of its world transform; every joint keeps
its channel list and order (position channels hold the joint's offset), End Sites their
names, OFFSETs their file values where position channels override them. When the Motion no
longer fits that layout (other joints, a rotation its channels cannot express), the plain
layout is written instead.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.formats.bvh_build import CHANNELS
from motionlang.formats.bvh_read import FPS_TOLERANCE
from motionlang.formats.units import resolve_unit
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES, chain, matrix_to_chain
from motionlang.kinematics.skeleton import Joint
from motionlang.utils.atomic import atomic_write

_ZXY = np.stack([AXES["z"], AXES["x"], AXES["y"]])


def _letters(axes: np.ndarray) -> str | None:
    """``"zxy"`` for distinct positive coordinate axes (k, 3), else None."""
    out = ""
    for a in axes:
        hit = [c for c, v in AXES.items() if np.allclose(a, v, atol=1e-12)]
        if not hit or hit[0] in out:
            return None
        out += hit[0]
    return out


def _fmt(v: float) -> str:
    """A channel value: 6 decimals (1e-6 degrees, 1e-8 m in cm files), no trailing zeros."""
    s = f"{v:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _fmt_offset(v: float) -> str:
    """An OFFSET value: 9 significant digits, so that a file's own ``1.87007e-05`` or
    ``-452.225`` comes back as written."""
    s = f"{v:.9g}"
    return "0" if s == "-0" else s


def _plain(jt: Joint) -> bool:
    return np.allclose(jt.pre, np.eye(3), atol=1e-12) and np.allclose(jt.post, np.eye(3),
                                                                      atol=1e-12)


def _euler(R: np.ndarray, letters: str) -> np.ndarray:
    """(T, k) degrees of the chain ``letters`` for rotations (T, 3, 3), unwrapped over time
    so that angles do not jump by 360 degrees."""
    axes = np.stack([AXES[c] for c in letters])
    return np.rad2deg(np.unwrap(matrix_to_chain(R, axes), axis=0))


def write_bvh(motion: Motion, path: str | Path, unit: float | str | None = None) -> None:
    """Write any Motion as a Y-up BVH file that Blender imports.

    A Motion whose ``meta["bvh_hierarchy"]`` still matches its skeleton is written in that
    file layout (module docstring). Otherwise: joints whose rotation already is a BVH
    Euler chain (``pre = post = I``, coordinate DOF axes, ``world = I``) keep their
    channels and angles exactly (3 of them unless the motion came from a BVH); every other
    joint gets ``Zrotation Xrotation Yrotation`` channels from its local rotation
    ``world @ pre @ R(dofs) @ post @ world^T``. Leaf joints without DOFs become End Sites.

    Args:
        unit: metres per written length unit (or ``"m"``, ``"cm"``, ``"mm"``, ``"inch"``);
            default: the skeleton's own unit for BVH-born motions, centimetres otherwise.
    """
    from_bvh = motion.source_format == "bvh"
    hier = motion.meta.get("bvh_hierarchy")
    u = resolve_unit(unit)[1] if unit is not None else \
        motion.skeleton.file_unit if from_bvh or isinstance(hier, dict) else 0.01
    body = _user_layout(motion, hier, u) if isinstance(hier, dict) else None
    if body is None:
        body = _plain_layout(motion, u, from_bvh)
    header, columns = body
    frame_time = motion.meta.get("frame_time")
    if isinstance(frame_time, float) and (from_bvh or isinstance(hier, dict)) and \
            frame_time > 0 and abs(frame_time * motion.fps - 1) <= FPS_TOLERANCE:
        time_line = f"Frame Time: {frame_time:.10g}"   # the file's own value
    else:
        time_line = f"Frame Time: {1.0 / motion.fps:.8f}"
    data = np.stack(columns, axis=1) if columns else np.zeros((motion.n_frames, 0))
    with atomic_write(path) as fh:
        fh.write("\n".join(header) + "\n")
        fh.write(f"MOTION\nFrames: {motion.n_frames}\n{time_line}\n")
        for row in data:
            fh.write(" ".join(_fmt(v) for v in row) + "\n")


# ------------------------------------------------------------------------------ the file's own
def _anchor(nodes: list[dict], r: int, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """World translation (3,) in written units and rotation (3, 3) of the dropped chain
    ``nodes[0..r-1]`` posed with its stored ``values`` (``scale``: written units per
    file unit)."""
    t, R = np.zeros(3), np.eye(3)
    for a in range(r):
        n = nodes[a]
        L = np.array(n["offset"], dtype=float) * scale
        axes, angles = [], []
        for c, v in zip(n["channels"], n["values"]):
            axis, kind = CHANNELS[c]
            if kind == "position":
                k = "xyz".index(axis)
                L[k] = float(v) * scale + (L[k] if a == 0 else 0.0)
            else:
                axes.append(AXES[axis])
                angles.append(np.deg2rad(float(v)))
        t = t + R @ L
        R = R @ chain(np.array(axes).reshape(-1, 3), np.array(angles))
    return t, R


def _rotation(letters: str, axes: np.ndarray, angles: np.ndarray, plain: bool,
              local) -> np.ndarray | None:
    """(T, k) degrees of a rotation in the channel order ``letters``: the angles as they are
    when the DOF chain already is that order, else converted from the matrices ``local()``
    (needs all 3 channels); None when the channels cannot hold it."""
    if plain and _letters(axes) == letters:
        return np.rad2deg(angles)
    if plain and len(axes) == 0:
        return np.zeros((len(angles), len(letters)))
    if len(letters) != 3:
        return None
    return _euler(local(), letters)


def _user_layout(motion: Motion, hier: dict, u: float):
    """(header lines, channel columns (T,) each) in the layout of ``hier``, or None when the
    Motion does not fit it."""
    sk = motion.skeleton
    try:
        nodes, scale = hier["nodes"], float(hier["file_unit"]) / u
        r = next(i for i, n in enumerate(nodes) if n["joint"] is not None)
        fits = (np.allclose(sk.world, np.eye(3), atol=1e-12)
                and [n["joint"] for n in nodes[r:]] == sk.names
                and all(nodes[i]["parent"] == i - 1 for i in range(r + 1))
                and all(sk.joints[i - r].parent == nodes[i]["parent"] - r
                        for i in range(r + 1, len(nodes))))
        if not fits:
            return None
        tA, RA = _anchor(nodes, r, scale)
    except (KeyError, TypeError, ValueError, StopIteration):
        return None  # not a layout this writer made sense of
    T = motion.n_frames
    columns: dict[int, list[np.ndarray]] = {}
    for i, n in enumerate(nodes):
        pos = {c[0].lower(): k for k, c in enumerate(n["channels"]) if c.endswith("position")}
        letters = "".join(c[0].lower() for c in n["channels"] if c.endswith("rotation"))
        if i < r:  # a dropped ancestor: its stored constant values
            vals = [float(v) * (scale if c.endswith("position") else 1.0)
                    for c, v in zip(n["channels"], n["values"])]
            columns[i] = [np.full(T, v) for v in vals]
            continue
        jt = sk.joints[i - r]
        if n["end_site"]:
            if jt.ndof or n["channels"]:
                return None
            continue
        if i == r:
            p = (motion.root_translation + jt.offset) / u
            if r > 0:
                move = (p - tA) @ RA          # RA^T (p - tA), row-wise
            else:
                move = motion.root_translation / u
                if any(a not in pos and np.abs(move[:, k]).max() > 1e-9
                       for k, a in enumerate("xyz")):
                    return None
            plain = jt.ndof == 0 and _plain(jt) and np.array_equal(RA, np.eye(3))
            rot = _rotation(letters, sk.root_axes, motion.root_rotation, plain,
                            lambda: RA.T @ chain(sk.root_axes, motion.root_rotation) @ jt.pre
                            @ chain(jt.axes, motion.joint_angles[:, sk.dof_slice(0)]) @ jt.post)
        else:
            move = np.repeat(jt.offset[None] / u, T, axis=0)
            angles = motion.joint_angles[:, sk.dof_slice(i - r)]
            rot = _rotation(letters, jt.axes, angles, _plain(jt),
                            lambda: jt.pre @ chain(jt.axes, angles) @ jt.post)
        if rot is None or (i == r and r > 0 and len(pos) < 3):
            return None
        rot_cols = iter(rot.T)
        columns[i] = [move[:, "xyz".index(c[0].lower())] if c.endswith("position")
                      else next(rot_cols) for c in n["channels"]]
    header = ["HIERARCHY"]
    kids: list[list[int]] = [[] for _ in nodes]
    for i, n in enumerate(nodes[1:], start=1):
        kids[n["parent"]].append(i)

    def offset_line(i: int) -> str:
        n = nodes[i]
        own = np.array(n["offset"], dtype=float) * scale
        if i >= r and not (i == r and r > 0):  # the skeleton's offset, unless a channel overrides
            pos = {c[0].lower() for c in n["channels"] if c.endswith("position")}
            joint = sk.joints[i - r].offset / u
            own = np.array([own[k] if a in pos and i > 0 else joint[k]
                            for k, a in enumerate("xyz")])
        return "OFFSET " + " ".join(_fmt_offset(v) for v in own)

    def emit(i: int, depth: int) -> None:
        n, ind = nodes[i], "\t" * depth
        if n["end_site"]:
            head = "End Site" + (f" {n['name']}" if n["name"] else "")
        else:
            head = f"{'ROOT' if i == 0 else 'JOINT'} {n['name']}"
        header.extend([ind + head, ind + "{", f"{ind}\t{offset_line(i)}"])
        if not n["end_site"]:
            header.append(f"{ind}\tCHANNELS {len(n['channels'])} {' '.join(n['channels'])}")
        for c in kids[i]:
            emit(c, depth + 1)
        header.append(ind + "}")

    emit(0, 0)
    return header, [c for i in range(len(nodes)) for c in columns.get(i, [])]


# ------------------------------------------------------------------------------ plain
def _plain_layout(motion: Motion, u: float, from_bvh: bool):
    """(header lines, channel columns) of the plain layout (``write_bvh``'s docstring)."""
    sk = motion.skeleton
    W = sk.world
    plain_world = np.allclose(W, np.eye(3), atol=1e-12)
    kids = [sk.children(j) for j in range(len(sk))]
    columns: list[np.ndarray] = []   # (T,) channel values in file order
    header: list[str] = ["HIERARCHY"]

    def plain(j: int) -> bool:
        return plain_world and _plain(sk.joints[j])

    # ---- root
    root = sk.joints[0]
    root_letters = _letters(sk.root_axes)
    ang0 = motion.joint_angles[:, sk.dof_slice(0)]
    if plain(0) and root.ndof == 0 and root_letters is not None and \
            (from_bvh or len(root_letters) == 3):
        offset0 = root.offset / u
        pos = motion.root_translation / u
        rot_names = [f"{c.upper()}rotation" for c in root_letters]
        rot_vals = np.rad2deg(motion.root_rotation)
    else:
        offset0 = np.zeros(3)
        pos = (motion.root_translation + root.offset) @ W.T / u
        local = chain(sk.root_axes, motion.root_rotation) @ root.pre @ chain(root.axes, ang0) \
            @ root.post
        rot_names = ["Zrotation", "Xrotation", "Yrotation"]
        rot_vals = _euler(W @ local @ W.T, "zxy")
    order = motion.meta.get("bvh_root_channels") if from_bvh else None
    want = sorted(["Xposition", "Yposition", "Zposition"] + rot_names)
    if not (isinstance(order, list) and sorted(order) == want
            and [c for c in order if c.endswith("rotation")] == rot_names):
        order = ["Xposition", "Yposition", "Zposition"] + rot_names
    for c in order:
        columns.append(pos[:, "XYZ".index(c[0])] if c.endswith("position")
                       else rot_vals[:, rot_names.index(c)])
    names = [n.replace(" ", "_") or "joint" for n in sk.names]
    header += [f"ROOT {names[0]}", "{", f"\tOFFSET {' '.join(_fmt_offset(v) for v in offset0)}",
               f"\tCHANNELS {len(order)} {' '.join(order)}"]

    # ---- the rest, depth first
    def emit(j: int, depth: int) -> None:
        jt, ind = sk.joints[j], "\t" * depth
        off = " ".join(_fmt_offset(v) for v in (W @ jt.offset) / u)
        if not kids[j] and jt.ndof == 0:
            header.extend([f"{ind}End Site", f"{ind}{{", f"{ind}\tOFFSET {off}", f"{ind}}}"])
            return
        letters = _letters(jt.axes)
        angles = motion.joint_angles[:, sk.dof_slice(j)]
        if plain(j) and letters is not None and (from_bvh or len(letters) == 3):
            chans = [f"{c.upper()}rotation" for c in letters]
            vals = np.rad2deg(angles)
        else:
            chans = ["Zrotation", "Xrotation", "Yrotation"]
            vals = _euler(W @ jt.pre @ chain(jt.axes, angles) @ jt.post @ W.T, "zxy")
        columns.extend(vals.T)
        header.extend([f"{ind}JOINT {names[j]}", f"{ind}{{", f"{ind}\tOFFSET {off}",
                       f"{ind}\tCHANNELS {len(chans)} {' '.join(chans)}"])
        for c in kids[j]:
            emit(c, depth + 1)
        if not kids[j]:  # a leaf with DOFs still needs an end
            header.extend([f"{ind}\tEnd Site", f"{ind}\t{{", f"{ind}\t\tOFFSET 0 0 0",
                           f"{ind}\t}}"])
        header.append(f"{ind}}}")

    for c in kids[0]:
        emit(c, 1)
    if not kids[0]:
        header.extend(["\tEnd Site", "\t{", "\t\tOFFSET 0 0 0", "\t}"])
    header.append("}")
    return header, columns

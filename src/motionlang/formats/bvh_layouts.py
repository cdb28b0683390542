"""The two layouts ``write_bvh`` writes a Motion in, each as (HIERARCHY lines, channel
columns (T,) each): the file's own (:func:`own_layout`) and the plain one
(:func:`plain_layout`); see :mod:`motionlang.formats.bvh_write`.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from motionlang.formats.bvh_build import CHANNELS
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES, chain, matrix_to_chain
from motionlang.kinematics.skeleton import Joint


def _letters(axes: np.ndarray) -> str | None:
    """``"zxy"`` for distinct positive coordinate axes (k, 3), else None."""
    out = ""
    for a in axes:
        hit = [c for c, v in AXES.items() if np.allclose(a, v, atol=1e-12)]
        if not hit or hit[0] in out:
            return None
        out += hit[0]
    return out


def _fmt_offset(v: float) -> str:
    """An OFFSET value: 9 significant digits, so that a file's own ``1.87007e-05`` or
    ``-452.225`` comes back as written."""
    s = f"{v:.9g}"
    return "0" if s == "-0" else s


def _plain(jt: Joint) -> bool:
    """Whether the joint's rotation is its DOF chain alone (``pre = post = I``)."""
    return np.allclose(jt.pre, np.eye(3), atol=1e-12) and np.allclose(jt.post, np.eye(3),
                                                                      atol=1e-12)


def _euler(R: np.ndarray, letters: str) -> np.ndarray:
    """(T, k) degrees of the chain ``letters`` for rotations (T, 3, 3), unwrapped over time
    so that angles do not jump by 360 degrees."""
    axes = np.stack([AXES[c] for c in letters])
    return np.rad2deg(np.unwrap(matrix_to_chain(R, axes), axis=0))


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


class _Fit(NamedTuple):
    """How a Motion sits in a file's own layout: ``nodes[r]`` is its root, ``scale`` written
    units per file unit, ``t``/``R`` the world translation and rotation of the dropped chain."""
    nodes: list
    r: int
    scale: float
    t: np.ndarray
    R: np.ndarray


def own_layout(motion: Motion, hier: dict, u: float):
    """(header lines, channel columns (T,) each) in the layout of ``hier``, or None when the
    Motion does not fit it."""
    fit = _fit(motion.skeleton, hier, u)
    if fit is None:
        return None
    columns = _own_columns(motion, fit, u)
    if columns is None:
        return None
    header = _own_header(motion.skeleton, fit, u)
    return header, [c for i in range(len(fit.nodes)) for c in columns.get(i, [])]


def _fit(sk, hier: dict, u: float) -> _Fit | None:
    """Where the skeleton sits in ``hier``, or None when its joints do not match."""
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
    return _Fit(nodes, r, scale, tA, RA)


def _own_columns(motion: Motion, fit: _Fit, u: float) -> dict[int, list] | None:
    """Node index -> its channel columns (T,) each, or None when a node's channels cannot
    hold the Motion."""
    sk, T, nodes, r = motion.skeleton, motion.n_frames, fit.nodes, fit.r
    columns: dict[int, list[np.ndarray]] = {}
    for i, n in enumerate(nodes):
        pos = {c[0].lower(): k for k, c in enumerate(n["channels"]) if c.endswith("position")}
        letters = "".join(c[0].lower() for c in n["channels"] if c.endswith("rotation"))
        if i < r:  # a dropped ancestor: its stored constant values
            vals = [float(v) * (fit.scale if c.endswith("position") else 1.0)
                    for c, v in zip(n["channels"], n["values"])]
            columns[i] = [np.full(T, v) for v in vals]
            continue
        jt = sk.joints[i - r]
        if n["end_site"]:
            if jt.ndof or n["channels"]:
                return None
            continue
        if i == r:
            moved = _own_root(motion, fit, pos, letters, u)
            if moved is None:
                return None
            move, rot = moved
        else:
            move = np.repeat(jt.offset[None] / u, T, axis=0)
            angles = motion.joint_angles[:, sk.dof_slice(i - r)]
            rot = _rotation(letters, jt.axes, angles, _plain(jt),
                            lambda jt=jt, angles=angles: jt.pre @ chain(jt.axes, angles) @ jt.post)
        if rot is None or (i == r and r > 0 and len(pos) < 3):
            return None
        rot_cols = iter(rot.T)
        columns[i] = [move[:, "xyz".index(c[0].lower())] if c.endswith("position")
                      else next(rot_cols) for c in n["channels"]]
    return columns


def _own_root(motion: Motion, fit: _Fit, pos: dict, letters: str, u: float):
    """(position (T, 3) in written units, rotation columns or None) of the Motion's root
    node, relative to the dropped chain; None when a root move has no channel to go in."""
    sk, r, tA, RA = motion.skeleton, fit.r, fit.t, fit.R
    jt = sk.joints[0]
    p = (motion.root_translation + jt.offset) / u
    if r > 0:
        move = (p - tA) @ RA          # RA^T (p - tA), row-wise
    else:
        move = motion.root_translation / u
        if any(a not in pos and np.abs(move[:, k]).max() > 1e-9 for k, a in enumerate("xyz")):
            return None
    plain = jt.ndof == 0 and _plain(jt) and np.array_equal(RA, np.eye(3))
    rot = _rotation(letters, sk.root_axes, motion.root_rotation, plain,
                    lambda: RA.T @ chain(sk.root_axes, motion.root_rotation) @ jt.pre
                    @ chain(jt.axes, motion.joint_angles[:, sk.dof_slice(0)]) @ jt.post)
    return move, rot


def _own_header(sk, fit: _Fit, u: float) -> list[str]:
    """The HIERARCHY lines of the file's own layout, OFFSETs from the skeleton."""
    nodes, header = fit.nodes, ["HIERARCHY"]
    kids: list[list[int]] = [[] for _ in nodes]
    for i, n in enumerate(nodes[1:], start=1):
        kids[n["parent"]].append(i)

    stack = [(0, 0, False)]   # depth first without recursion: chains of 2,000 joints
    while stack:
        i, depth, closing = stack.pop()
        n, ind = nodes[i], "\t" * depth
        if closing:
            header.append(ind + "}")
            continue
        if n["end_site"]:
            head = "End Site" + (f" {n['name']}" if n["name"] else "")
        else:
            head = f"{'ROOT' if i == 0 else 'JOINT'} {n['name']}"
        header.extend([ind + head, ind + "{", f"{ind}\t{_own_offset(sk, fit, i, u)}"])
        if not n["end_site"]:
            header.append(f"{ind}\tCHANNELS {len(n['channels'])} {' '.join(n['channels'])}")
        stack.append((i, depth, True))
        stack.extend((c, depth + 1, False) for c in reversed(kids[i]))
    return header


def _own_offset(sk, fit: _Fit, i: int, u: float) -> str:
    """The OFFSET line of node ``i``: the file's value where a position channel overrides
    it (or for a dropped ancestor), else the skeleton's."""
    n, r = fit.nodes[i], fit.r
    own = np.array(n["offset"], dtype=float) * fit.scale
    if i >= r and not (i == r and r > 0):
        pos = {c[0].lower() for c in n["channels"] if c.endswith("position")}
        joint = sk.joints[i - r].offset / u
        own = np.array([own[k] if a in pos and i > 0 else joint[k] for k, a in enumerate("xyz")])
    return "OFFSET " + " ".join(_fmt_offset(v) for v in own)


# ------------------------------------------------------------------------------ plain
def plain_layout(motion: Motion, u: float, from_bvh: bool):
    """(header lines, channel columns) of the plain layout (``write_bvh``'s docstring)."""
    sk = motion.skeleton
    plain_world = np.allclose(sk.world, np.eye(3), atol=1e-12)
    offset0, order, columns = _plain_root(motion, u, from_bvh, plain_world)
    tree = _PlainTree(motion, u, from_bvh, plain_world, columns)
    tree.header += [f"ROOT {tree.names[0]}", "{",
                    f"\tOFFSET {' '.join(_fmt_offset(v) for v in offset0)}",
                    f"\tCHANNELS {len(order)} {' '.join(order)}"]
    for c in tree.kids[0]:
        tree.emit(c, 1)
    if not tree.kids[0]:
        tree.header.extend(["\tEnd Site", "\t{", "\t\tOFFSET 0 0 0", "\t}"])
    tree.header.append("}")
    return tree.header, columns


def _plain_root(motion: Motion, u: float, from_bvh: bool, plain_world: bool):
    """(root OFFSET (3,), root channel names, their columns (T,) each) of the plain layout:
    the root's own channels when they already are a BVH chain, else ZXY of its rotation."""
    sk = motion.skeleton
    W, root = sk.world, sk.joints[0]
    root_letters = _letters(sk.root_axes)
    ang0 = motion.joint_angles[:, sk.dof_slice(0)]
    if plain_world and _plain(root) and root.ndof == 0 and root_letters is not None and \
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
    # a BVH-born motion keeps its file's root channel order when the channels still fit
    order = motion.meta.get("bvh_root_channels") if from_bvh else None
    want = sorted(["Xposition", "Yposition", "Zposition"] + rot_names)
    if not (isinstance(order, list) and sorted(order) == want
            and [c for c in order if c.endswith("rotation")] == rot_names):
        order = ["Xposition", "Yposition", "Zposition"] + rot_names
    columns = [pos[:, "XYZ".index(c[0])] if c.endswith("position")
               else rot_vals[:, rot_names.index(c)] for c in order]
    return offset0, order, columns


class _PlainTree:
    """The non-root joints of the plain layout, written depth first into ``header`` and
    ``columns``."""

    def __init__(self, motion: Motion, u: float, from_bvh: bool, plain_world: bool,
                 columns: list[np.ndarray]):
        self.motion, self.u, self.from_bvh, self.plain_world = motion, u, from_bvh, plain_world
        sk = motion.skeleton
        self.kids = [sk.children(j) for j in range(len(sk))]
        self.names = [n.replace(" ", "_") or "joint" for n in sk.names]
        self.header: list[str] = ["HIERARCHY"]
        self.columns = columns   # (T,) channel values in file order

    def emit(self, top: int, top_depth: int) -> None:
        """Joint ``top`` and its subtree at ``top_depth`` tabs (depth first, without
        recursion: a chain of 2,000 joints is a valid rig)."""
        sk, header, kids = self.motion.skeleton, self.header, self.kids
        stack = [(top, top_depth, False)]
        while stack:
            j, depth, closing = stack.pop()
            ind = "\t" * depth
            if closing:
                if not kids[j]:  # a leaf with DOFs still needs an end
                    header.extend([f"{ind}\tEnd Site", f"{ind}\t{{", f"{ind}\t\tOFFSET 0 0 0",
                                   f"{ind}\t}}"])
                header.append(f"{ind}}}")
                continue
            W, jt = sk.world, sk.joints[j]
            off = " ".join(_fmt_offset(v) for v in (W @ jt.offset) / self.u)
            if not kids[j] and jt.ndof == 0:
                header.extend([f"{ind}End Site", f"{ind}{{", f"{ind}\tOFFSET {off}",
                               f"{ind}}}"])
                continue
            chans, vals = self._rotation(j)
            self.columns.extend(vals.T)
            header.extend([f"{ind}JOINT {self.names[j]}", f"{ind}{{", f"{ind}\tOFFSET {off}",
                           f"{ind}\tCHANNELS {len(chans)} {' '.join(chans)}"])
            stack.append((j, depth, True))
            stack.extend((c, depth + 1, False) for c in reversed(kids[j]))

    def _rotation(self, j: int) -> tuple[list[str], np.ndarray]:
        """Channel names and (T, k) degrees of joint ``j``: its own chain when that already
        is a BVH one, else ZXY of its local rotation."""
        sk = self.motion.skeleton
        W, jt = sk.world, sk.joints[j]
        letters = _letters(jt.axes)
        angles = self.motion.joint_angles[:, sk.dof_slice(j)]
        if self.plain_world and _plain(jt) and letters is not None and \
                (self.from_bvh or len(letters) == 3):
            return [f"{c.upper()}rotation" for c in letters], np.rad2deg(angles)
        return (["Zrotation", "Xrotation", "Yrotation"],
                _euler(W @ jt.pre @ chain(jt.axes, angles) @ jt.post @ W.T, "zxy"))

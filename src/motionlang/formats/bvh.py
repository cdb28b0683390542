"""Biovision hierarchy (BVH): read any Euler channel order, write any Motion.

BVH conventions: Y up; a joint's rotation is the product of its rotation channels in file
order (``CHANNELS 3 Zrotation Xrotation Yrotation`` -> ``Rz @ Rx @ Ry``), which is exactly
``Skeleton``'s DOF chain with ``pre = post = I``; angles in degrees; root position channels
are added to the root ``OFFSET``; lengths in an unstated unit (guessed from the skeleton's
size unless given). ``End Site`` nodes become DOF-free joints named ``<parent>_end``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES, chain, matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton
from motionlang.utils.atomic import atomic_write

MAX_ABS = 1e12  # largest magnitude accepted for any number; FK would overflow beyond
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "inch": 0.0254}
_CHANNELS = {f"{c}{kind}": (c.lower(), kind) for c in "XYZ" for kind in ("position", "rotation")}


def _unit(unit: float | str | None, default: float) -> float:
    """Metres per BVH length unit from a number, a name (``"cm"``) or None (``default``)."""
    if unit is None:
        return default
    if isinstance(unit, str):
        if unit.lower() not in UNITS:
            raise ValueError(f"unknown unit {unit!r}; use one of {sorted(UNITS)} or metres")
        return UNITS[unit.lower()]
    if not (math.isfinite(unit) and unit > 0):
        raise ValueError(f"unit must be a positive number of metres, got {unit}")
    return float(unit)


def guess_unit(rest_positions: np.ndarray) -> float:
    """Metres per file unit from the rest pose (J, 3) in file units: a human is 1-2.5 m tall,
    so an extent below 10 means metres, below 500 centimetres, otherwise millimetres."""
    extent = float(np.ptp(rest_positions, axis=0).max()) if len(rest_positions) else 0.0
    if 0 < extent < 10:
        return 1.0
    return 0.01 if extent < 500 else 0.001


# ------------------------------------------------------------------------------ reading
class _Tokens:
    """Whitespace tokens of the hierarchy part, with their 1-based line numbers."""

    def __init__(self, path: Path, lines: list[str]):
        self.path, self.lines = path, lines
        self.ln, self.buf = 0, []

    def next(self, what: str) -> tuple[str, int]:
        while not self.buf:
            if self.ln >= len(self.lines):
                raise MotionFormatError(self.path, f"file ends early, expected {what}",
                                        line=max(len(self.lines), 1))
            self.ln += 1
            self.buf = self.lines[self.ln - 1].split()[::-1]
        return self.buf.pop(), self.ln

    def expect(self, word: str) -> int:
        tok, ln = self.next(repr(word))
        if tok.upper() != word.upper():
            raise MotionFormatError(self.path, f"expected {word!r}, got {tok[:40]!r}", line=ln)
        return ln

    def number(self, what: str, integer: bool = False) -> float:
        tok, ln = self.next(what)
        try:
            v = int(tok) if integer else float(tok)
        except ValueError:
            raise MotionFormatError(self.path, f"malformed number {tok[:40]!r} for {what}",
                                    line=ln) from None
        if not integer and not math.isfinite(v):
            raise MotionFormatError(self.path, f"non-finite {what}: {tok!r}", line=ln)
        if abs(v) > MAX_ABS:
            raise MotionFormatError(self.path, f"{what} out of range: {tok[:40]!r}", line=ln)
        return v


def _parse_hierarchy(tk: _Tokens) -> list[dict]:
    """Nodes in file (depth-first) order: name, parent, offset (file units), channels, line."""
    tk.expect("HIERARCHY")
    nodes: list[dict] = []
    stack: list[int] = []
    tok, ln = tk.next("ROOT")
    if tok.upper() != "ROOT":
        raise MotionFormatError(tk.path, f"expected 'ROOT', got {tok[:40]!r}", line=ln)
    while True:
        if tok.upper() in ("ROOT", "JOINT"):
            if (tok.upper() == "ROOT") != (not stack):
                raise MotionFormatError(tk.path, f"unexpected {tok!r}", line=ln)
            if stack and nodes[stack[-1]]["end"]:
                raise MotionFormatError(tk.path, "an End Site cannot have children", line=ln)
            name, _ = tk.next("a joint name")
            kind = "joint"
        elif tok.upper() == "END":
            tk.expect("Site")
            if not stack or nodes[stack[-1]]["end"]:
                raise MotionFormatError(tk.path, "misplaced End Site", line=ln)
            name, kind = f"{nodes[stack[-1]]['name']}_end", "end"
        else:
            raise MotionFormatError(tk.path, f"unexpected {tok[:40]!r} in HIERARCHY", line=ln)
        tk.expect("{")
        nodes.append({"name": name, "parent": stack[-1] if stack else -1, "offset": None,
                      "channels": [], "line": ln, "end": kind == "end"})
        stack.append(len(nodes) - 1)
        while True:
            tok, ln = tk.next("'}'")
            up = tok.upper()
            node = nodes[stack[-1]]
            if up == "OFFSET":
                node["offset"] = np.array([tk.number("OFFSET") for _ in range(3)])
            elif up == "CHANNELS":
                if node["end"]:
                    raise MotionFormatError(tk.path, "End Site cannot have CHANNELS", line=ln)
                n = int(tk.number("the channel count", integer=True))
                if not 0 <= n <= 6:
                    raise MotionFormatError(tk.path, f"bad channel count {n}", line=ln)
                chans = [tk.next("a channel name")[0] for _ in range(n)]
                bad = [c for c in chans if c not in _CHANNELS]
                if bad or len(set(chans)) != n:
                    raise MotionFormatError(tk.path, f"bad channel list {chans}", line=ln)
                node["channels"] = chans
            elif tok == "}":
                if node["offset"] is None:
                    raise MotionFormatError(tk.path, f"{node['name']!r} has no OFFSET", line=ln)
                stack.pop()
                if not stack:
                    return nodes
            else:
                break  # a child node starts
        if len(nodes) > 10000:
            raise MotionFormatError(tk.path, "more than 10000 joints", line=ln)


def read_bvh(path: str | Path, unit: float | str | None = None) -> Motion:
    """Read a BVH file.

    Args:
        unit: metres per file length unit (or ``"m"``, ``"cm"``, ``"mm"``, ``"in"``);
            guessed from the skeleton's size when None (:func:`guess_unit`).

    Returns:
        Motion with a Y-up skeleton named ``"bvh:<stem>"``; ``meta["path"]``,
        ``meta["bvh_root_channels"]`` (the root's channel names, for writing back).

    Raises:
        MotionFormatError: on malformed content, naming the file and line.
    """
    path = Path(path)
    try:
        lines = path.read_bytes().decode("utf-8-sig", errors="replace").splitlines()
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    tk = _Tokens(path, lines)
    nodes = _parse_hierarchy(tk)
    tk.expect("MOTION")
    tk.expect("Frames:")
    n_frames = int(tk.number("the frame count", integer=True))
    tk.expect("Frame")
    ln = tk.expect("Time:")
    dt = tk.number("the frame time")
    if tk.buf:
        raise MotionFormatError(path, "unexpected text after the frame time", line=ln)
    if dt <= 0:
        raise MotionFormatError(path, f"frame time must be positive, got {dt}", line=ln)
    if n_frames <= 0:
        raise MotionFormatError(path, "no frames (Frames: 0)", line=ln)
    C = sum(len(n["channels"]) for n in nodes)
    if n_frames > len(lines) - tk.ln:  # checked before allocating (T, C)
        raise MotionFormatError(path, f"file truncated: 'Frames: {n_frames}' but only "
                                      f"{len(lines) - tk.ln} lines follow", line=len(lines))
    data = np.empty((n_frames, C))
    t = 0
    for ln in range(tk.ln + 1, len(lines) + 1):
        toks = lines[ln - 1].split()
        if not toks:
            continue
        if t >= n_frames:
            raise MotionFormatError(path, f"more frame lines than 'Frames: {n_frames}'", line=ln)
        if len(toks) != C:
            raise MotionFormatError(path, f"frame {t} has {len(toks)} values, expected {C}",
                                    line=ln)
        try:
            row = np.array(toks, dtype=float)
        except ValueError:
            bad = next(x for x in toks if not _is_float(x))
            raise MotionFormatError(path, f"malformed number {bad[:40]!r}", line=ln) from None
        if not np.all(np.isfinite(row)):
            raise MotionFormatError(path, "non-finite value (NaN or inf)", line=ln, frame=t)
        if np.abs(row).max(initial=0.0) > MAX_ABS:
            raise MotionFormatError(path, "value out of range", line=ln, frame=t)
        data[t] = row
        t += 1
    if t < n_frames:
        raise MotionFormatError(path, f"file truncated: {t} of {n_frames} frames",
                                line=max(len(lines), 1))
    return _build(path, nodes, data, dt, unit)


def _is_float(x: str) -> bool:
    try:
        float(x)
        return True
    except ValueError:
        return False


def _build(path: Path, nodes: list[dict], data: np.ndarray, dt: float, unit) -> Motion:
    T = len(data)
    rest = np.zeros((len(nodes), 3))
    for i, n in enumerate(nodes):
        rest[i] = n["offset"] + (rest[n["parent"]] if n["parent"] >= 0 else 0.0)
    if not np.all(np.isfinite(rest)):
        raise MotionFormatError(path, "OFFSET values too large", line=nodes[0]["line"])
    u = _unit(unit, guess_unit(rest))
    joints, angle_cols = [], []
    root_axes, root_rot_cols, trans = [], [], np.zeros((T, 3))
    col = 0
    names_seen: set[str] = set()
    for i, n in enumerate(nodes):
        name = n["name"]
        k = 2
        if name in names_seen and not n["end"]:
            raise MotionFormatError(path, f"duplicate joint name {name!r}", line=n["line"])
        while name in names_seen:  # End Site names may collide with real joints
            name, k = f"{n['name']}{k}", k + 1
        names_seen.add(name)
        offset = n["offset"].copy()
        axes = []
        for c in n["channels"]:
            axis, kind = _CHANNELS[c]
            if kind == "rotation":
                (root_axes if i == 0 else axes).append(AXES[axis])
                (root_rot_cols if i == 0 else angle_cols).append(col)
            elif i == 0:
                trans[:, "xyz".index(axis)] = data[:, col]
            else:
                # position channels on inner joints (e.g. LAFAN1) must be constant: they
                # then replace the OFFSET; moving inner joints cannot be represented.
                vals = data[:, col]
                if np.ptp(vals) > 1e-6 * max(1.0, float(np.abs(vals).max())):
                    raise MotionFormatError(path, f"joint {name!r} has animated position "
                                                  "channels (not supported)", line=n["line"])
                offset["xyz".index(axis)] = vals[0]
            col += 1
        joints.append(Joint(name, n["parent"], offset * u, axes=np.array(axes).reshape(-1, 3),
                            dof_names=tuple(f"{name}_{c}" for c in n["channels"]
                                            if c.endswith("rotation") and i > 0)))
    try:
        sk = Skeleton(joints, world=np.eye(3), root_axes=np.array(root_axes).reshape(-1, 3),
                      file_unit=u, name=f"bvh:{path.stem}")
    except SkeletonError as exc:
        raise MotionFormatError(path, str(exc)) from None
    fps = 1.0 / dt
    if abs(fps - round(fps)) < 1e-3 * fps:  # 0.0083333 s -> 120 fps, not 120.0005
        fps = float(round(fps))
    rad = np.deg2rad(data)
    try:
        motion = Motion(sk, fps, trans * u, rad[:, root_rot_cols].reshape(T, -1),
                        rad[:, angle_cols].reshape(T, -1), name=path.stem, source_format="bvh",
                        meta={"path": str(path), "bvh_root_channels": list(nodes[0]["channels"]),
                              "frame_time": dt})
    except MotionFormatError as exc:
        raise MotionFormatError(path, exc.reason, frame=exc.frame) from None
    return motion


# ------------------------------------------------------------------------------ writing
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
    s = f"{v:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def write_bvh(motion: Motion, path: str | Path, unit: float | str | None = None) -> None:
    """Write any Motion as a Y-up BVH file that Blender imports.

    Joints whose rotation already is a BVH Euler chain (``pre = post = I``, coordinate DOF
    axes, ``world = I``) keep their channels and angles exactly (3 of them unless the motion
    came from a BVH); every other joint gets ``Zrotation Xrotation Yrotation`` channels from
    its local rotation ``world @ pre @ R(dofs) @ post @ world^T`` (unwrapped over time so
    angles do not jump by 360 degrees). Leaf joints without DOFs become End Sites.

    Args:
        unit: metres per written length unit (or ``"m"``, ``"cm"``, ``"mm"``, ``"in"``);
            default: the skeleton's own unit for BVH-born motions, centimetres otherwise.
    """
    sk = motion.skeleton
    from_bvh = motion.source_format == "bvh"
    u = _unit(unit, sk.file_unit if from_bvh else 0.01)
    W = sk.world
    plain_world = np.allclose(W, np.eye(3), atol=1e-12)
    T = motion.n_frames
    kids = [sk.children(j) for j in range(len(sk))]
    columns: list[np.ndarray] = []   # (T,) channel values in file order
    header: list[str] = ["HIERARCHY"]

    def plain(j: int) -> bool:
        jt = sk.joints[j]
        return (plain_world and np.allclose(jt.pre, np.eye(3), atol=1e-12)
                and np.allclose(jt.post, np.eye(3), atol=1e-12))

    def euler(R: np.ndarray) -> np.ndarray:
        return np.rad2deg(np.unwrap(matrix_to_chain(R, _ZXY), axis=0))

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
        rot_vals = euler(W @ local @ W.T)
    order = motion.meta.get("bvh_root_channels") if from_bvh else None
    want = sorted(["Xposition", "Yposition", "Zposition"] + rot_names)
    if not (isinstance(order, list) and sorted(order) == want
            and [c for c in order if c.endswith("rotation")] == rot_names):
        order = ["Xposition", "Yposition", "Zposition"] + rot_names
    for c in order:
        columns.append(pos[:, "XYZ".index(c[0])] if c.endswith("position")
                       else rot_vals[:, rot_names.index(c)])
    names = [n.replace(" ", "_") or "joint" for n in sk.names]
    header += [f"ROOT {names[0]}", "{", f"\tOFFSET {' '.join(_fmt(v) for v in offset0)}",
               f"\tCHANNELS {len(order)} {' '.join(order)}"]

    # ---- the rest, depth first
    def emit(j: int, depth: int) -> None:
        jt, ind = sk.joints[j], "\t" * depth
        off = " ".join(_fmt(v) for v in (W @ jt.offset) / u)
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
            vals = euler(W @ jt.pre @ chain(jt.axes, angles) @ jt.post @ W.T)
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
    frame_time = motion.meta.get("frame_time") if from_bvh else None
    if not (isinstance(frame_time, float) and abs(frame_time * motion.fps - 1) < 1e-3):
        frame_time = 1.0 / motion.fps
    data = np.stack(columns, axis=1) if columns else np.zeros((T, 0))
    with atomic_write(path) as fh:
        fh.write("\n".join(header) + "\n")
        fh.write(f"MOTION\nFrames: {T}\nFrame Time: {frame_time:.8f}\n")
        for row in data:
            fh.write(" ".join(_fmt(v) for v in row) + "\n")

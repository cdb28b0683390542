"""Acclaim AMC motions and flat AMC channel arrays, for skeletons from
:func:`motionlang.formats.asf.read_asf`.

:func:`motion_to_channels` / :func:`motion_from_channels` convert to and from the flat AMC
layout (root channels in the ASF ``order``, then each bone's DOFs in ``dof`` order, bones in
skeleton order, which is the ASF bonedata order whenever that lists parents first — CMU does).
That is the column order of ``cmu35WalkJog.mat`` (Taylor 2006): its first 90 rows equal
35_01.amc's channels at frames 1, 5, 9, ... exactly.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.formats.asf import ROT_DOFS, parse_float, read_asf, read_lines
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES
from motionlang.kinematics.skeleton import Skeleton
from motionlang.utils import limits
from motionlang.utils.atomic import atomic_write

_INTEGER = re.compile(r"-?[0-9]+")  # ASCII digits only: "²".isdigit() is True, int() fails


# ------------------------------------------------------------------------------ channel layout
def _layout(skeleton: Skeleton) -> tuple[list[str], list[tuple[str, int]],
                                         list[tuple[str, int, int]]]:
    """How flat AMC channels map onto a Motion of ``skeleton``.

    Returns:
        root_order: the 6 root channel names (``TX ... RZ``);
        root_map: per root channel, ``("t", column of root_translation)`` or
            ``("r", column of root_rotation)``;
        cols: per bone channel in file order, ``(bone name, channel index, joint_angles
            column)``.

    Raises:
        SkeletonError: if the skeleton does not have the ASF layout.
    """
    info = getattr(skeleton, "asf_layout", None)
    root_order = info["root_order"] if info else ["TX", "TY", "TZ", "RX", "RY", "RZ"]
    axis_row = {}
    for i, a in enumerate(skeleton.root_axes):
        for c, v in AXES.items():
            if np.allclose(a, v):
                axis_row[c] = i
    root_map = []
    for t in root_order:
        c = t[1].lower()
        if t[0] == "T":
            root_map.append(("t", "xyz".index(c)))
        elif c in axis_row:
            root_map.append(("r", axis_row[c]))
        else:
            raise SkeletonError(f"skeleton {skeleton.name!r} has no root rotation about {c}")
    if len(axis_row) != len(skeleton.root_axes) or len(root_map) != 6:
        raise SkeletonError(f"skeleton {skeleton.name!r} does not have an ASF root")
    cols = []
    ch = 6
    for j, joint in enumerate(skeleton.joints):
        if joint.ndof == 0:
            continue
        if info and joint.name in info["dofs"]:
            dofs = info["dofs"][joint.name]
        else:
            dofs = sorted(n.rsplit("_", 1)[-1] for n in joint.dof_names)
            if any(d not in ROT_DOFS for d in dofs):
                raise SkeletonError(f"skeleton {skeleton.name!r} is not an ASF skeleton "
                                    f"(joint {joint.name!r} has DOFs {joint.dof_names})")
        start = skeleton.dof_slice(j).start
        for d in dofs:
            name = f"{joint.name}_{d}"
            if name not in joint.dof_names:
                raise SkeletonError(f"skeleton {skeleton.name!r} is not an ASF skeleton "
                                    f"(DOF {name!r} missing)")
            cols.append((joint.name, ch, start + joint.dof_names.index(name)))
            ch += 1
    if len(cols) != skeleton.ndof:
        raise SkeletonError(f"skeleton {skeleton.name!r} is not an ASF skeleton")
    return root_order, root_map, cols


def motion_from_channels(skeleton: Skeleton, channels_deg: np.ndarray, fps: float,
                         name: str | None = None) -> Motion:
    """Build a Motion from flat AMC channels.

    Args:
        skeleton: from :func:`read_asf`.
        channels_deg: (T, C) root position in ASF length units and angles in degrees, in
            the ASF channel order (C = 6 + DOFs; 62 for CMU, the layout of cmu35WalkJog.mat).
        fps: frames per second.
    """
    ch = np.asarray(channels_deg, dtype=float)
    _, root_map, cols = _layout(skeleton)
    if ch.ndim != 2 or ch.shape[1] != 6 + len(cols):
        raise MotionFormatError(None, f"expected (T, {6 + len(cols)}) channels for skeleton "
                                      f"{skeleton.name!r}, got {ch.shape}")
    T = len(ch)
    trans, rot = np.zeros((T, 3)), np.zeros((T, len(skeleton.root_axes)))
    for i, (kind, col) in enumerate(root_map):
        if kind == "t":
            trans[:, col] = ch[:, i] * skeleton.file_unit
        else:
            rot[:, col] = np.deg2rad(ch[:, i])
    angles = np.zeros((T, skeleton.ndof))
    src = np.array([c for _, c, _ in cols], dtype=int)
    dst = np.array([d for _, _, d in cols], dtype=int)
    angles[:, dst] = np.deg2rad(ch[:, src])
    return Motion(skeleton, float(fps), trans, rot, angles, name=name or skeleton.name,
                  source_format="amc")


def motion_to_channels(motion: Motion) -> np.ndarray:
    """(T, C) flat AMC channels (root position in ASF units, angles in degrees)."""
    sk = motion.skeleton
    _, root_map, cols = _layout(sk)
    T = motion.n_frames
    out = np.empty((T, 6 + len(cols)))
    for i, (kind, col) in enumerate(root_map):
        out[:, i] = (motion.root_translation[:, col] / sk.file_unit if kind == "t"
                     else np.rad2deg(motion.root_rotation[:, col]))
    for _, c, d in cols:
        out[:, c] = np.rad2deg(motion.joint_angles[:, d])
    return out


# ------------------------------------------------------------------------------ AMC
def read_amc(path: str | Path, skeleton: Skeleton, fps: float = 120.0) -> Motion:
    """Read an AMC motion for ``skeleton`` (from :func:`read_asf`).

    Every bone with DOFs must appear once per frame with exactly its DOF count of values.

    Returns:
        Motion at ``fps`` (CMU: 120), ``source_format="amc"``, ``meta["path"]``,
        ``meta["first_frame"]`` (the first frame number in the file).

    Raises:
        MotionFormatError: malformed content (file and line named), or a file or motion
            beyond the limits (``utils.limits``).
    """
    path = Path(path)
    fps = _positive_fps(path, fps)
    lines = read_lines(path)
    try:
        _, root_map, cols = _layout(skeleton)
    except SkeletonError as exc:
        raise MotionFormatError(path, str(exc)) from None
    info = getattr(skeleton, "asf_layout", None)
    amc = _AmcFrames(path, _bone_slots(skeleton, cols), 6 + len(cols),
                     degrees=info["degrees"] if info else True)
    amc.feed(lines)
    limits.check_motion(path, len(amc.frames), len(skeleton), amc.width)
    ch = np.stack(amc.frames)
    if not amc.degrees:
        rot_ch = [i for i, (k, _) in enumerate(root_map) if k == "r"] + list(range(6, amc.width))
        ch[:, rot_ch] = np.rad2deg(ch[:, rot_ch])
    motion = motion_from_channels(skeleton, ch, fps, name=path.stem)
    motion.meta.update(path=str(path), first_frame=amc.numbers[0])
    try:
        motion.validate(str(path))
    except MotionFormatError as exc:
        if exc.frame is None:
            raise
        raise MotionFormatError(path, exc.reason, frame=exc.frame) from None
    return motion


def _positive_fps(path: Path, fps) -> float:
    """``fps`` as a float, or MotionFormatError unless finite and positive."""
    try:
        fps = float(fps)
    except (TypeError, ValueError):
        fps = float("nan")
    if not (math.isfinite(fps) and fps > 0):
        raise MotionFormatError(path, f"frame rate must be positive, got {fps}")
    return fps


def _bone_slots(skeleton: Skeleton, cols) -> dict[str, tuple[int, int]]:
    """Bone name -> (first channel, channel count) in a frame row; DOF-less bones get
    ``(0, 0)`` because AMC files may list them with no values."""
    slots: dict[str, tuple[int, int]] = {"root": (0, 6)}
    for name, c, _ in cols:
        s, n = slots.get(name, (c, 0))
        slots[name] = (s, n + 1)
    for j in skeleton.joints:
        if j.ndof == 0 and j.parent >= 0 and not j.name.endswith("_end"):
            slots.setdefault(j.name, (0, 0))
    return slots


class _AmcFrames:
    """The frames of one AMC file, gathered line by line into rows of ``width`` channels."""

    def __init__(self, path: Path, slots: dict[str, tuple[int, int]], width: int,
                 degrees: bool):
        self.path, self.slots, self.width, self.degrees = path, slots, width, degrees
        self.max_frames = limits.current().max_frames
        self.frames: list[np.ndarray] = []
        self.numbers: list[int] = []
        self.seen: set[str] = set()
        self.row: np.ndarray | None = None

    def feed(self, lines: list[str]) -> None:
        """Parse every line: headers, frame numbers and bone values."""
        for ln, text in enumerate(lines, start=1):
            tok = text.split("#", 1)[0].split()
            if not tok:
                continue
            if tok[0].startswith(":"):
                self._header(tok, ln)
            elif len(tok) == 1 and _INTEGER.fullmatch(tok[0]):
                self._start_frame(tok[0], ln)
            elif self.row is None:
                raise MotionFormatError(self.path, "expected a frame number, got "
                                                   f"{text.strip()[:40]!r}", line=ln)
            else:
                self._bone_values(tok, ln)
        if self.row is None:
            raise MotionFormatError(self.path, "no frames", line=len(lines))
        self._close(len(lines))

    def _header(self, tok: list[str], ln: int) -> None:
        """A ``:KEYWORD`` line; only the angle unit matters."""
        if self.row is not None:
            raise MotionFormatError(self.path, f"header {tok[0]!r} after the first frame",
                                    line=ln)
        key = tok[0].upper()
        if key == ":DEGREES":
            self.degrees = True
        elif key == ":RADIANS":
            self.degrees = False

    def _start_frame(self, number: str, ln: int) -> None:
        """A frame number: close the frame before and open a new row."""
        if len(number.lstrip("-")) > 15:  # int() of 4,300+ digits raises; none is real
            raise MotionFormatError(self.path, f"frame number {number[:20]}... out of range",
                                    line=ln)
        if self.row is not None:
            self._close(ln)
            if len(self.frames) >= self.max_frames:
                limits.check(self.path, "max_frames", len(self.frames) + 1, "frame count",
                             line=ln)
        self.numbers.append(int(number))
        self.row, self.seen = np.zeros(self.width), set()

    def _bone_values(self, tok: list[str], ln: int) -> None:
        """A bone's name and values, stored in the open row."""
        path, name = self.path, tok[0]
        if name not in self.slots:
            raise MotionFormatError(path, f"unknown bone {name[:40]!r}", line=ln)
        if name in self.seen:
            raise MotionFormatError(path, f"bone {name!r} given twice in one frame", line=ln)
        start, n = self.slots[name]
        if len(tok) - 1 != n:
            raise MotionFormatError(path, f"bone {name!r} needs {n} values, got {len(tok) - 1}",
                                    line=ln)
        for i, t in enumerate(tok[1:]):
            self.row[start + i] = parse_float(t, path, ln, f"bone {name!r}")
        self.seen.add(name)

    def _close(self, ln: int) -> None:
        """Keep the open row once every bone with DOFs has been given."""
        missing = [n for n, (_, k) in self.slots.items() if k and n not in self.seen]
        if missing:
            raise MotionFormatError(self.path, f"frame {self.numbers[-1]} lacks bone(s) "
                                               f"{missing[:5]}", line=ln)
        self.frames.append(self.row)


def read_asf_amc(asf_path: str | Path, amc_path: str | Path, fps: float = 120.0) -> Motion:
    """Read a skeleton and one of its motions."""
    return read_amc(amc_path, read_asf(asf_path), fps=fps)


def _fmt(v: float) -> str:
    s = f"{v:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def write_amc(motion: Motion, path: str | Path) -> None:
    """Write ``motion`` (of an ASF skeleton) as an AMC file, angles in degrees.

    Raises:
        SkeletonError: if the motion's skeleton does not come from an ASF.
    """
    sk = motion.skeleton
    root_order, _, cols = _layout(sk)
    ch = motion_to_channels(motion)
    groups: list[tuple[str, int, int]] = []
    for name, c, _ in cols:
        if groups and groups[-1][0] == name:
            groups[-1] = (name, groups[-1][1], c + 1)
        else:
            groups.append((name, c, c + 1))
    first = motion.meta.get("first_frame", 1)  # keep the source's frame numbering
    first = first if isinstance(first, int) else 1
    with atomic_write(path) as fh:
        fh.write(f"# written by motionlang from {motion.name}\n:FULLY-SPECIFIED\n:DEGREES\n")
        for t in range(motion.n_frames):
            fh.write(f"{first + t}\n")
            fh.write("root " + " ".join(_fmt(v) for v in ch[t, :6]) + "\n")
            for name, a, b in groups:
                fh.write(name + " " + " ".join(_fmt(v) for v in ch[t, a:b]) + "\n")

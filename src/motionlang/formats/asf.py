"""Acclaim ASF skeletons, as used by the CMU motion capture database.

Conventions (Acclaim spec, as CMU files use them):

* Lengths: ``:units length L`` means a file length ``v`` is ``v / L`` inches, so one file
  unit is ``0.0254 / L`` metres (CMU: ``L = 0.45``). The AMC root position uses the same unit.
* A bone's ``axis ax ay az XYZ`` gives the fixed rotation ``C = Rz(az) Ry(ay) Rx(ax)`` (the
  letters name the order in which the rotations are applied); the bone's local rotation is
  ``C @ M @ C^T`` with ``M`` the DOF rotations applied in the same letter order
  (``M = Rz Ry Rx`` for ``dof rx ry rz``). The root uses its ``axis`` order the same way;
  its ``orientation`` becomes a fixed ``pre`` rotation and its ``position`` (0 in CMU files,
  ignored by common tools) is ignored. This order is the one that keeps CMU feet planted:
  the reverse (``Rx Ry Rz``) makes the stance foot of 35_01 slide 2-3x faster.
* ``direction`` is a unit vector in the global rest frame (Y up); ``length`` its length.

Skeleton model: a node per bone placed at the bone's start (the root node, then one node per
bone, plus ``<bone>_end`` nodes at the tips of leaf bones), ``pre = C``, ``post = C^T``, and a
node's offset is its parent bone's ``direction * length``. Because ``Skeleton`` composes a
DOF chain left to right, a bone's DOF axes (and its ``joint_angles`` columns) are stored in
composition order, e.g. ``rz, ry, rx`` with names ``lfemur_rz, lfemur_ry, lfemur_rx``.

The motion side (AMC files, flat channel arrays) is :mod:`motionlang.formats.amc`.
"""
from __future__ import annotations

import heapq
import math
import re
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.kinematics.rotations import AXES, chain
from motionlang.kinematics.skeleton import Joint, Skeleton
from motionlang.utils import limits

INCH = 0.0254
MAX_ABS = 1e12  # largest magnitude accepted for any number in a file
ROT_DOFS = {"rx": "x", "ry": "y", "rz": "z"}


# ------------------------------------------------------------------------------ helpers
PARSE_FACTOR = 8  # memory of the lines as Python strings, and more, per byte of file


def read_lines(path: Path) -> list[str]:
    """The lines of a text file (UTF-8, BOM and bad bytes tolerated)."""
    limits.check_file(path, PARSE_FACTOR)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    return raw.decode("utf-8-sig", errors="replace").splitlines()


def parse_float(tok: str, path, line: int, what: str) -> float:
    """A finite number of at most ``MAX_ABS`` from a token, else MotionFormatError."""
    try:
        v = float(tok)
    except ValueError:
        raise MotionFormatError(path, f"malformed number {tok[:40]!r} in {what}",
                                line=line) from None
    if not math.isfinite(v):
        raise MotionFormatError(path, f"non-finite number {tok!r} in {what}", line=line)
    if abs(v) > MAX_ABS:  # no real length or angle is this big; FK would overflow
        raise MotionFormatError(path, f"number {tok!r} out of range in {what}", line=line)
    return v


def _euler(order: str, angles_rad) -> np.ndarray:
    """Rotation applying ``order[0]`` first: e.g. ``XYZ`` -> ``Rz @ Ry @ Rx``; (3, 3)."""
    axes = np.stack([AXES[c] for c in reversed(order.lower())])
    return chain(axes, np.asarray(angles_rad, dtype=float)[::-1])


def _check_order(order: str, path, line: int) -> str:
    order = order.upper()
    if len(order) != 3 or sorted(order) != ["X", "Y", "Z"]:
        raise MotionFormatError(path, f"bad rotation order {order!r} (want e.g. XYZ)", line=line)
    return order


class _Bone:
    def __init__(self, line: int):
        self.line = line
        self.name: str | None = None
        self.direction = np.zeros(3)
        self.length = 0.0
        self.axis = np.zeros(3)
        self.order = "XYZ"
        self.dofs: list[str] = []
        self.limits: list[tuple[float, float]] = []


_LIMIT = re.compile(r"\(\s*([^\s()]+)\s+([^\s()]+)\s*\)")


def _limits(text: str, path, line: int) -> list[tuple[float, float]]:
    """``(lo hi)`` pairs on one line (``inf`` allowed: some ASFs leave DOFs unbounded)."""
    body = text.strip()
    if body.lower().startswith("limits"):
        body = body[6:]
    pairs = _LIMIT.findall(body)
    if not pairs or _LIMIT.sub("", body).strip():
        raise MotionFormatError(path, f"malformed limits {body.strip()[:40]!r}", line=line)
    out = []
    for lo, hi in pairs:
        try:
            a, b = float(lo), float(hi)
        except ValueError:
            raise MotionFormatError(path, f"malformed limits ({lo[:20]} {hi[:20]})",
                                    line=line) from None
        if math.isnan(a) or math.isnan(b) or a > b:
            raise MotionFormatError(path, f"bad limits ({lo[:20]} {hi[:20]})", line=line)
        out.append((a, b))
    return out


# ------------------------------------------------------------------------------ ASF
def read_asf(path: str | Path) -> Skeleton:
    """Read an ASF skeleton (see the module docstring for the node layout).

    Returns:
        a ``Skeleton`` named ``"cmu:<file stem>"``, Y-up (``world = I``), offsets in metres,
        ``file_unit`` = metres per ASF length unit. The file's AMC layout is kept in the
        attribute ``asf_layout`` (dict: ``root_order``, ``dofs`` per bone in file order,
        ``limits`` per bone as (lo, hi) pairs in the file's angle unit, ``degrees``).

    Raises:
        MotionFormatError: on any malformed content, naming the file and line, or a file
            or skeleton beyond the limits (``utils.limits``).
    """
    path = Path(path)
    lines = read_lines(path)
    max_bones = limits.current().max_joints - 1  # the root is a node too
    length_scale, deg = 1.0, True
    root_order, root_axis, root_orient = ["TX", "TY", "TZ", "RX", "RY", "RZ"], "XYZ", np.zeros(3)
    bones: dict[str, _Bone] = {}
    children: dict[str, list[str]] = {}
    parent_of: dict[str, str] = {}
    section, bone, hier_seen = None, None, False
    for ln, text in enumerate(lines, start=1):
        tok = text.split("#", 1)[0].split()
        if not tok:
            continue
        key = tok[0].lower()
        if key.startswith(":"):
            if bone is not None:
                raise MotionFormatError(path, "section starts inside an unfinished bone", line=ln)
            section = key
            hier_seen |= key == ":hierarchy"
            continue
        if section == ":units":
            if key == "length" and len(tok) > 1:
                length_scale = parse_float(tok[1], path, ln, "units length")
                if length_scale <= 0:
                    raise MotionFormatError(path, "units length must be positive", line=ln)
            elif key == "angle" and len(tok) > 1:
                if tok[1].lower() not in ("deg", "rad"):
                    raise MotionFormatError(path, f"unknown angle unit {tok[1]!r}", line=ln)
                deg = tok[1].lower() == "deg"
        elif section == ":root":
            if key == "order":
                root_order = [t.upper() for t in tok[1:]]
                if sorted(root_order) != sorted(["TX", "TY", "TZ", "RX", "RY", "RZ"]):
                    raise MotionFormatError(path, f"unsupported root order {tok[1:]}", line=ln)
            elif key == "axis":
                root_axis = _check_order(tok[1] if len(tok) > 1 else "", path, ln)
            elif key == "orientation":
                if len(tok) != 4:
                    raise MotionFormatError(path, "root orientation needs 3 values", line=ln)
                root_orient = np.array([parse_float(t, path, ln, "root orientation") for t in tok[1:]])
        elif section == ":bonedata":
            if key == "begin":
                if bone is not None:
                    raise MotionFormatError(path, "'begin' inside a bone", line=ln)
                bone = _Bone(ln)
            elif bone is None:
                raise MotionFormatError(path, f"{tok[0][:40]!r} outside begin/end", line=ln)
            elif key == "end":
                if not bone.name:
                    raise MotionFormatError(path, "bone without a name", line=ln)
                if bone.limits and len(bone.limits) != len(bone.dofs):
                    raise MotionFormatError(path, f"bone {bone.name!r} has {len(bone.dofs)} "
                                                  f"DOFs but {len(bone.limits)} limits", line=ln)
                if bone.name in bones or bone.name == "root":
                    raise MotionFormatError(path, f"duplicate bone name {bone.name!r}", line=ln)
                if len(bones) >= max_bones:
                    limits.check(path, "max_joints", len(bones) + 2, "joint count", line=ln)
                bones[bone.name] = bone
                bone = None
            elif key == "name" and len(tok) == 2:
                bone.name = tok[1]
            elif key == "direction":
                if len(tok) != 4:
                    raise MotionFormatError(path, "direction needs 3 values", line=ln)
                bone.direction = np.array([parse_float(t, path, ln, "direction") for t in tok[1:]])
            elif key == "length":
                if len(tok) != 2:
                    raise MotionFormatError(path, "length needs 1 value", line=ln)
                bone.length = parse_float(tok[1], path, ln, "length")
            elif key == "axis":
                if len(tok) != 5:
                    raise MotionFormatError(path, "axis needs 3 angles and an order", line=ln)
                bone.axis = np.array([parse_float(t, path, ln, "axis") for t in tok[1:4]])
                bone.order = _check_order(tok[4], path, ln)
            elif key == "dof":
                dofs = [t.lower() for t in tok[1:]]
                bad = [d for d in dofs if d not in ROT_DOFS]
                if bad or len(set(dofs)) != len(dofs):
                    raise MotionFormatError(path, f"unsupported or repeated DOFs {tok[1:]} "
                                                  "(only rx ry rz are supported)", line=ln)
                bone.dofs = dofs
            elif key == "limits" or key.startswith("("):
                bone.limits += _limits(text.split("#", 1)[0], path, ln)
            elif key in ("id", "bodymass", "cofmass"):
                pass  # ids are not used for linking; masses are not modelled
            else:
                raise MotionFormatError(path, f"unknown bone field {tok[0]!r}", line=ln)
        elif section == ":hierarchy":
            if key in ("begin", "end"):
                continue
            par = tok[0]
            if par != "root" and par not in bones:
                raise MotionFormatError(path, f"unknown parent bone {par!r} in hierarchy", line=ln)
            for child in tok[1:]:
                if child not in bones:
                    raise MotionFormatError(path, f"unknown bone {child!r} in hierarchy", line=ln)
                if child in parent_of:
                    raise MotionFormatError(path, f"bone {child!r} has two parents", line=ln)
                parent_of[child] = par
                children.setdefault(par, []).append(child)
    if bone is not None:
        raise MotionFormatError(path, "file ends inside a bone (missing 'end')", line=len(lines))
    if not hier_seen:
        raise MotionFormatError(path, "no :hierarchy section", line=len(lines))
    unit = INCH / length_scale
    if not math.isfinite(unit):
        raise MotionFormatError(path, f"units length {length_scale:g} is too small")
    ang = (lambda a: np.deg2rad(a)) if deg else (lambda a: np.asarray(a, dtype=float))

    # nodes parents first, each time the first bone in bonedata order whose parent is
    # placed: a heap of the bones ready to place, n log n whatever order the file lists
    order = {n: i for i, n in enumerate(bones)}
    names = list(bones)
    placed: dict[str, int] = {"root": 0}
    joints = [Joint("root", -1, np.zeros(3), pre=_euler(root_axis, ang(root_orient)))]
    ready = sorted(order[c] for c in children.get("root", []))
    while ready:
        name = names[heapq.heappop(ready)]
        b, par = bones[name], parent_of[name]
        offset = np.zeros(3) if par == "root" else _bone_vector(bones[par], unit, path)
        C = _euler(b.order, ang(b.axis))
        comp = [d for d in reversed(b.order.lower()) if "r" + d in b.dofs]
        placed[name] = len(joints)
        joints.append(Joint(name, placed[par], offset,
                            axes=np.array([AXES[d] for d in comp]).reshape(-1, 3),
                            pre=C, post=C.T, dof_names=tuple(f"{name}_r{d}" for d in comp)))
        if not children.get(name):
            joints.append(Joint(f"{name}_end", len(joints) - 1, _bone_vector(b, unit, path)))
        for child in children.get(name, ()):
            heapq.heappush(ready, order[child])
    if len(placed) <= len(bones):
        first = next(n for n in bones if n not in placed)
        raise MotionFormatError(path, f"bone {first!r} is {_unplaced_why(first, parent_of)} "
                                      "in the hierarchy", line=bones[first].line)
    limits.check(path, "max_joints", len(joints), "joint count (bones and end points)")
    root_axes = np.array([AXES[c] for c in reversed(root_axis.lower())])
    try:
        sk = Skeleton(joints, world=np.eye(3), root_axes=root_axes, file_unit=unit,
                      name=f"cmu:{path.stem}", mirror=np.diag([-1.0, 1.0, 1.0]))
    except SkeletonError as exc:
        raise MotionFormatError(path, str(exc)) from None
    # the AMC layout, kept on the skeleton so that writers reproduce the file's channel order
    sk.asf_layout = {"root_order": root_order, "degrees": deg,
                     "dofs": {n: list(b.dofs) for n, b in bones.items()},
                     "limits": {n: list(b.limits) for n, b in bones.items() if b.limits}}
    return sk


def _unplaced_why(name: str, parent_of: dict[str, str]) -> str:
    """Why a bone never got placed: its chain of parents ends off the root, or loops."""
    seen = set()
    while name in parent_of and name not in seen:
        seen.add(name)
        name = parent_of[name]
    return "in a cycle" if name in seen else "not connected to the root"


def _bone_vector(b: _Bone, unit: float, path) -> np.ndarray:
    """Bone vector (3,) in metres: direction (normalised) times length."""
    norm = float(np.linalg.norm(b.direction))
    if b.length != 0 and not (np.isfinite(norm) and norm > 1e-12):
        raise MotionFormatError(path, f"bone {b.name!r} has a zero or invalid direction",
                                line=b.line)
    v = b.direction / norm * b.length * unit if b.length != 0 else np.zeros(3)
    if not np.all(np.isfinite(v)):
        raise MotionFormatError(path, f"bone {b.name!r} has a non-finite length", line=b.line)
    return v

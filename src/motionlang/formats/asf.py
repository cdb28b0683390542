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
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, SkeletonError

# MAX_ABS, PARSE_FACTOR, ROT_DOFS, parse_float and read_lines stay importable from here
from motionlang.formats.asf_parse import (  # noqa: F401
    MAX_ABS,
    PARSE_FACTOR,
    ROT_DOFS,
    AsfBone,
    AsfSections,
    parse_float,
    read_lines,
)
from motionlang.kinematics.rotations import AXES, chain
from motionlang.kinematics.skeleton import Joint, Skeleton
from motionlang.utils import limits

INCH = 0.0254


def _euler(order: str, angles_rad) -> np.ndarray:
    """Rotation applying ``order[0]`` first: e.g. ``XYZ`` -> ``Rz @ Ry @ Rx``; (3, 3)."""
    axes = np.stack([AXES[c] for c in reversed(order.lower())])
    return chain(axes, np.asarray(angles_rad, dtype=float)[::-1])


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
    asf = AsfSections(path)
    asf.feed(lines)
    unit = INCH / asf.length_scale
    if not math.isfinite(unit):
        raise MotionFormatError(path, f"units length {asf.length_scale:g} is too small")
    joints = _place_joints(asf, unit)
    limits.check(path, "max_joints", len(joints), "joint count (bones and end points)")
    root_axes = np.array([AXES[c] for c in reversed(asf.root_axis.lower())])
    try:
        sk = Skeleton(joints, world=np.eye(3), root_axes=root_axes, file_unit=unit,
                      name=f"cmu:{path.stem}", mirror=np.diag([-1.0, 1.0, 1.0]))
    except SkeletonError as exc:
        raise MotionFormatError(path, str(exc)) from None
    # the AMC layout, kept on the skeleton so that writers reproduce the file's channel order
    sk.asf_layout = {"root_order": asf.root_order, "degrees": asf.deg,
                     "dofs": {n: list(b.dofs) for n, b in asf.bones.items()},
                     "limits": {n: list(b.limits) for n, b in asf.bones.items() if b.limits}}
    return sk


def _place_joints(asf: AsfSections, unit: float) -> list[Joint]:
    """The skeleton's nodes, parents first; every bone must hang off the root."""
    path, bones, parent_of, children = asf.path, asf.bones, asf.parent_of, asf.children
    ang = (lambda a: np.deg2rad(a)) if asf.deg else (lambda a: np.asarray(a, dtype=float))
    # each time the first bone in bonedata order whose parent is placed: a heap of the
    # bones ready to place, n log n whatever order the file lists
    order = {n: i for i, n in enumerate(bones)}
    names = list(bones)
    placed: dict[str, int] = {"root": 0}
    joints = [Joint("root", -1, np.zeros(3), pre=_euler(asf.root_axis, ang(asf.root_orient)))]
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
    return joints


def _unplaced_why(name: str, parent_of: dict[str, str]) -> str:
    """Why a bone never got placed: its chain of parents ends off the root, or loops."""
    seen = set()
    while name in parent_of and name not in seen:
        seen.add(name)
        name = parent_of[name]
    return "in a cycle" if name in seen else "not connected to the root"


def _bone_vector(b: AsfBone, unit: float, path) -> np.ndarray:
    """Bone vector (3,) in metres: direction (normalised) times length."""
    norm = float(np.linalg.norm(b.direction))
    if b.length != 0 and not (np.isfinite(norm) and norm > 1e-12):
        raise MotionFormatError(path, f"bone {b.name!r} has a zero or invalid direction",
                                line=b.line)
    v = b.direction / norm * b.length * unit if b.length != 0 else np.zeros(3)
    if not np.all(np.isfinite(v)):
        raise MotionFormatError(path, f"bone {b.name!r} has a non-finite length", line=b.line)
    return v

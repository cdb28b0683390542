"""Skeleton: a tree of joints, each with a fixed offset and rotation and a chain of DOF axes.

One model covers the three source formats:

* BVH: ``pre = post = I``, DOF axes = the Euler channels in file order.
* ASF/AMC: a node per bone; ``pre = C`` and ``post = C^T`` (the ASF ``axis``), DOF axes
  from ``dof``; a node's ``offset`` is its parent bone's vector.
* MMM (KIT): one node per segment or revolute joint, ``pre`` = the segment transform's
  rotation, a single DOF axis per revolute joint.

Forward kinematics (``kinematics.fk``) composes, for joint j with parent p::

    W_j = W_p @ pre_j @ R(axes_j, angles_j) @ post_j
    x_j = x_p + W_p @ offset_j

Offsets are in metres. ``world`` maps the source's coordinate frame to motionlang's
canonical frame (Y up, metres), in which all positions are returned.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from motionlang.errors import SkeletonError

#: NUL and control characters: never part of a joint name
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


@dataclass
class Joint:
    """One node of the tree.

    Attributes:
        name: unique name.
        parent: index of the parent joint, -1 for the root (which must be joint 0).
        offset: (3,) metres, position relative to the parent, in the parent's frame.
        axes: (k, 3) unit DOF axes in the joint's frame after ``pre``; k may be 0.
        pre: (3, 3) fixed rotation before the DOF chain.
        post: (3, 3) fixed rotation after the DOF chain.
        dof_names: k names of the DOFs (e.g. ``"LKx_joint"`` or ``"Xrotation"``).
    """

    name: str
    parent: int
    offset: np.ndarray
    axes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    pre: np.ndarray = field(default_factory=lambda: np.eye(3))
    post: np.ndarray = field(default_factory=lambda: np.eye(3))
    dof_names: tuple[str, ...] = ()

    def __post_init__(self):
        self.offset = np.asarray(self.offset, dtype=float).reshape(3)
        self.axes = np.asarray(self.axes, dtype=float).reshape(-1, 3)
        self.pre = np.asarray(self.pre, dtype=float).reshape(3, 3)
        self.post = np.asarray(self.post, dtype=float).reshape(3, 3)
        if not self.dof_names:
            self.dof_names = tuple(f"{self.name}_{i}" for i in range(len(self.axes)))
        if len(self.dof_names) != len(self.axes):
            raise SkeletonError(f"joint {self.name!r}: {len(self.axes)} axes but "
                                f"{len(self.dof_names)} DOF names")

    @property
    def ndof(self) -> int:
        return len(self.axes)


@dataclass
class Skeleton:
    """A joint tree plus its frame conventions.

    Attributes:
        joints: joints in topological order (parents before children), root first.
        world: (3, 3) rotation from the source frame to the canonical Y-up frame.
        root_axes: (3, 3) axes of the root orientation DOF chain (intrinsic order).
        file_unit: metres per length unit of the source file (writers use it to write back
            in the same unit).
        name: a label, e.g. ``"mmm"``, ``"cmu:35"``.
        mirror: (3, 3) reflection across the body's sagittal plane, in the source frame.
        pairs: left/right joint name pairs used by mirroring (detected from names if None).
    """

    joints: list[Joint]
    world: np.ndarray = field(default_factory=lambda: np.eye(3))
    root_axes: np.ndarray = field(default_factory=lambda: np.eye(3)[[2, 0, 1]])
    file_unit: float = 1.0
    name: str = "skeleton"
    mirror: np.ndarray = field(default_factory=lambda: np.diag([-1.0, 1.0, 1.0]))
    pairs: list[tuple[str, str]] | None = None

    def __post_init__(self):
        self.world = np.asarray(self.world, dtype=float)
        self.root_axes = np.asarray(self.root_axes, dtype=float).reshape(-1, 3)
        self.mirror = np.asarray(self.mirror, dtype=float)
        names = [j.name for j in self.joints]
        for n in names:   # names are written back out: files, terminals, reports
            if not isinstance(n, str) or _CONTROL.search(n):
                raise SkeletonError(f"joint name {n!r}: names must be text without NUL or "
                                    f"control characters")
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise SkeletonError(f"duplicate joint names: {dup}")
        if not self.joints or self.joints[0].parent != -1:
            raise SkeletonError("the first joint must be the root (parent -1)")
        for i, j in enumerate(self.joints[1:], start=1):
            if not 0 <= j.parent < i:
                raise SkeletonError(f"joint {j.name!r}: parent index {j.parent} must come "
                                    "before it")
        self._index = {n: i for i, n in enumerate(names)}
        starts = np.cumsum([0] + [j.ndof for j in self.joints])
        self._dof_slices = [slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]
        if self.pairs is None:
            self.pairs = detect_pairs(names)

    # ------------------------------------------------------------------ lookup
    @property
    def names(self) -> list[str]:
        return [j.name for j in self.joints]

    @property
    def parents(self) -> np.ndarray:
        return np.array([j.parent for j in self.joints])

    @property
    def offsets(self) -> np.ndarray:
        """(J, 3) metres."""
        return np.stack([j.offset for j in self.joints])

    @property
    def ndof(self) -> int:
        """Number of joint-angle DOFs (root orientation not included)."""
        return sum(j.ndof for j in self.joints)

    @property
    def dof_names(self) -> list[str]:
        return [n for j in self.joints for n in j.dof_names]

    def dof_slice(self, joint: int | str) -> slice:
        """Columns of ``Motion.joint_angles`` that belong to ``joint``."""
        return self._dof_slices[self.index(joint) if isinstance(joint, str) else joint]

    def index(self, name: str) -> int:
        try:
            return self._index[name]
        except KeyError:
            raise SkeletonError(f"unknown joint name {name!r} in skeleton {self.name!r}") from None

    def __contains__(self, name: str) -> bool:
        return name in self._index

    def __len__(self) -> int:
        return len(self.joints)

    def children(self, joint: int) -> list[int]:
        return [i for i, j in enumerate(self.joints) if j.parent == joint]


def detect_pairs(names: list[str]) -> list[tuple[str, str]]:
    """Find left/right joint pairs from common naming schemes.

    Recognised: ``Left*``/``Right*``, ``left*``/``right*``, ``l*``/``r*`` (CMU: ``lfemur``),
    ``L*``/``R*`` followed by an upper-case letter (MMM: ``LKx_joint``), ``*_l``/``*_r``,
    ``*_L``/``*_R`` (Bandai Namco: ``UpperArm_L``), ``*.L``/``*.R``.
    """
    present = set(names)
    pairs = []
    rules = [
        (r"^Left(.*)$", "Left{}", "Right{}"), (r"^left(.*)$", "left{}", "right{}"),
        (r"^L([A-Z].*)$", "L{}", "R{}"), (r"^l([a-z].*)$", "l{}", "r{}"),
        (r"^(.*)_l$", "{}_l", "{}_r"), (r"^(.*)_L$", "{}_L", "{}_R"),
        (r"^(.*)\.L$", "{}.L", "{}.R"),
    ]
    seen = set()
    for n in names:
        for pat, lf, rf in rules:
            m = re.match(pat, n)
            if m:
                left, right = lf.format(m.group(1)), rf.format(m.group(1))
                if left == n and right in present and n not in seen:
                    pairs.append((left, right))
                    seen.update((left, right))
                    break
    return pairs

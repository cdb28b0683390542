"""The one ``Motion`` type that every reader produces and every writer, feature and renderer
consumes."""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motionlang.errors import MotionFormatError, MotionlangError, SkeletonError
from motionlang.kinematics.rotations import chain
from motionlang.kinematics.skeleton import Skeleton
from motionlang.utils import limits

_EYE = np.eye(3)


@dataclass
class Motion:
    """A skeleton animated over time.

    Attributes:
        skeleton: the joint tree and its conventions.
        fps: frames per second.
        root_translation: (T, 3) metres, in the source frame (``skeleton.world`` maps it
            to the canonical Y-up frame).
        root_rotation: (T, k) radians, angles of the chain ``skeleton.root_axes``.
        joint_angles: (T, D) radians, DOF values of every joint in skeleton order
            (``skeleton.dof_slice(j)`` gives joint j's columns).
        name: a label (file stem by default).
        source_format: ``"mmm"``, ``"amc"``, ``"bvh"``, ``"mit"``, ``"synthetic"``...
        meta: free-form metadata (subject height, annotations, ground truth...).
    """

    skeleton: Skeleton
    fps: float
    root_translation: np.ndarray
    root_rotation: np.ndarray
    joint_angles: np.ndarray
    name: str = "motion"
    source_format: str = "unknown"
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        self.root_translation = np.asarray(self.root_translation, dtype=float)
        self.root_rotation = np.asarray(self.root_rotation, dtype=float)
        self.joint_angles = np.asarray(self.joint_angles, dtype=float)
        self.validate()

    def __repr__(self) -> str:
        # the arrays would print thousands of numbers: a summary, as a user reads it
        return (f"Motion({self.name!r}: {self.n_frames} frames at {self.fps:g} Hz "
                f"({self.n_frames / self.fps:.1f} s), {len(self.skeleton.joints)} joints, "
                f"from {self.source_format})")

    # ---------------------------------------------------------------- checks
    def validate(self, path: str | None = None) -> None:
        """Raise :class:`MotionFormatError` on wrong shapes, non-finite values or no frames."""
        where = path or self.meta.get("path") or self.name
        T = len(self.root_translation)
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise MotionFormatError(where, f"frame rate must be positive, got {self.fps}")
        if T == 0:
            raise MotionFormatError(where, "motion has no frames")
        if self.root_translation.shape != (T, 3):
            raise MotionFormatError(where, f"root_translation must be (T, 3), got "
                                           f"{self.root_translation.shape}")
        nroot = len(self.skeleton.root_axes)
        if self.root_rotation.shape != (T, nroot):
            raise MotionFormatError(where, f"root_rotation must be ({T}, {nroot}), got "
                                           f"{self.root_rotation.shape}")
        D = self.skeleton.ndof
        if self.joint_angles.shape != (T, D):
            raise MotionFormatError(where, f"joint_angles must be ({T}, {D}), got "
                                           f"{self.joint_angles.shape}")
        for arr, what in ((self.root_translation, "root position"),
                          (self.root_rotation, "root rotation"),
                          (self.joint_angles, "joint angles")):
            bad = ~np.isfinite(arr)
            if bad.any():
                frame = int(np.argwhere(bad)[0][0])
                raise MotionFormatError(where, f"non-finite value (NaN or inf) in {what}",
                                        frame=frame)

    # ---------------------------------------------------------------- basics
    @property
    def n_frames(self) -> int:
        return len(self.root_translation)

    def __len__(self) -> int:
        return self.n_frames

    @property
    def duration(self) -> float:
        """Seconds covered by the frames (``n_frames / fps``)."""
        return self.n_frames / self.fps

    def copy(self) -> Motion:
        return copy.deepcopy(self)

    def replace(self, **changes) -> Motion:
        """A new Motion with some fields replaced (arrays are not copied)."""
        kw = dict(skeleton=self.skeleton, fps=self.fps, root_translation=self.root_translation,
                  root_rotation=self.root_rotation, joint_angles=self.joint_angles,
                  name=self.name, source_format=self.source_format, meta=dict(self.meta))
        kw.update(changes)
        return Motion(**kw)

    def __getitem__(self, key: slice) -> Motion:
        """Slice frames; a step ``s`` divides the frame rate by ``s`` (``m[3::10]``)."""
        if not isinstance(key, slice):
            raise TypeError("Motion supports slicing only, e.g. motion[10:50] or motion[::4]")
        step = key.step or 1
        if step <= 0:
            raise ValueError("slice step must be positive")
        return self.replace(root_translation=self.root_translation[key],
                            root_rotation=self.root_rotation[key],
                            joint_angles=self.joint_angles[key], fps=self.fps / step)

    def between(self, start: float | None = None, end: float | None = None) -> Motion:
        """The frames from ``start`` to ``end`` seconds, both ends included (None: the
        motion's own start or end).

        Raises:
            MotionlangError: no frame in that span (naming the file and the motion's length).
        """
        if start is None and end is None:
            return self
        where = self.meta.get("path") or self.name
        for name, value in (("start", start), ("end", end)):
            if value is not None and not math.isfinite(value * self.fps):
                raise MotionlangError(f"{where}: the span's {name} must be a finite number "
                                      f"of seconds, got {value}")
        a = 0 if start is None else int(round(start * self.fps))
        b = self.n_frames - 1 if end is None else int(round(end * self.fps))
        if not 0 <= a < self.n_frames or b < a:
            raise MotionlangError(f"{where}: no frames between {start or 0:g} s and "
                                  f"{'the end' if end is None else f'{end:g} s'} (motion "
                                  f"lasts {self.duration:.2f} s)")
        return self[a:b + 1]

    def angle(self, dof_name: str) -> np.ndarray:
        """(T,) radians of one DOF, by name."""
        names = self.skeleton.dof_names
        if dof_name not in names:
            raise SkeletonError(f"unknown DOF {dof_name!r} in skeleton {self.skeleton.name!r}")
        return self.joint_angles[:, names.index(dof_name)]

    # ---------------------------------------------------------------- kinematics
    def global_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics in the source frame.

        Returns:
            rotations (T, J, 3, 3) joint frames to source frame, positions (T, J, 3) metres.
        """
        rots, pos = self._forward()
        return (np.stack(rots, axis=1) if rots else np.empty((self.n_frames, 0, 3, 3))), pos

    def _forward(self, needed: set[int] | None = None
                 ) -> tuple[list[np.ndarray | None], np.ndarray]:
        """Joint rotations as J blocks (T, 3, 3) and positions (T, J, 3) metres.

        Long takes spend their time here, hence: contiguous per-joint blocks (products of
        strided views of one (T, J, 3, 3) array are several times slower), identity
        factors skipped (BVH joints have ``pre = post = I``, End Sites no DOFs), and, given
        ``needed`` (joints closed under ancestors), the other joints not computed at all
        (their rotation None, their position left undefined): fingers and twist bones of a
        production rig are often half its joints.
        """
        sk = self.skeleton
        rots: list[np.ndarray | None] = []
        pos = np.empty((self.n_frames, len(sk), 3))
        for j, joint in enumerate(sk.joints):
            if needed is not None and j not in needed:
                rots.append(None)
                continue
            local = None if not joint.ndof else \
                chain(joint.axes, self.joint_angles[:, sk.dof_slice(j)])
            for fixed, before in ((joint.pre, True), (joint.post, False)):
                if not np.array_equal(fixed, _EYE):
                    local = fixed if local is None else fixed @ local if before else local @ fixed
            if joint.parent < 0:
                R = chain(sk.root_axes, self.root_rotation)
                pos[:, j] = self.root_translation + joint.offset
            else:
                R = rots[joint.parent]
                pos[:, j] = pos[:, joint.parent] + R @ joint.offset
            rots.append(R if local is None else R @ local)
        return rots, pos

    def positions(self, joints=None) -> np.ndarray:
        """(T, J, 3) joint positions in metres, canonical frame (Y up); with ``joints`` (a
        sequence of joint indices) only those, (T, len(joints), 3), computing no joint that
        is neither one of them nor an ancestor of one."""
        needed = None
        if joints is not None:
            joints = [int(j) for j in joints]
            needed = set()
            for j in joints:
                while j >= 0 and j not in needed:
                    needed.add(j)
                    j = self.skeleton.joints[j].parent
        _, pos = self._forward(needed)
        if joints is not None:
            pos = pos[:, joints]
        W = self.skeleton.world
        return pos if np.array_equal(W, _EYE) else pos @ W.T

    # ---------------------------------------------------------------- edits
    def resample(self, fps: float) -> Motion:
        """Linear re-timing to ``fps`` (angles unwrapped first, so +-pi crossings are safe).

        The first frame is kept; the last new frame is the last one inside the original
        time span. Decimation by an integer factor returns exact original frames.

        Raises:
            MotionFormatError: the re-timed motion would exceed the frame or memory limits
                (``utils.limits``), checked before anything is allocated.
        """
        if not (fps > 0 and np.isfinite(fps)):
            raise ValueError(f"target frame rate must be positive, got {fps}")
        if self.n_frames == 1:
            return self.replace(fps=float(fps))
        span = (self.n_frames - 1) / self.fps
        n_float = float(np.floor(span * fps + 1e-9) + 1)   # hours a frame: millions of them
        limits.check(self.name, "max_frames", n_float,   # inf compares above any limit
                     f"re-timing {span:,.3g} s to {fps:g} Hz: frame count")
        n_new = int(n_float)
        limits.check_motion(self.name, n_new, len(self.skeleton.joints),
                            self.joint_angles.shape[1] + 6)
        t_new = np.arange(n_new) / fps
        src = t_new * self.fps
        i0 = np.clip(np.floor(src + 1e-9).astype(int), 0, self.n_frames - 1)
        i1 = np.clip(i0 + 1, 0, self.n_frames - 1)
        w = np.clip(src - i0, 0.0, 1.0)[:, None]

        def interp(x, angular):
            if angular:
                x = np.unwrap(x, axis=0)
            return x[i0] * (1 - w) + x[i1] * w

        return self.replace(fps=float(fps),
                            root_translation=interp(self.root_translation, False),
                            root_rotation=interp(self.root_rotation, True),
                            joint_angles=interp(self.joint_angles, True))

    def mirror(self) -> Motion:
        """Swap left and right: reflect across the sagittal plane and exchange paired joints.

        Uses ``R' = S R S`` for every local rotation (S = ``skeleton.mirror``), which for a
        single-axis DOF means ``angle' = -(S a_partner . a_self) * angle_partner``. Mirroring
        twice gives the original motion back exactly.

        Raises:
            SkeletonError: if the skeleton is not symmetric in the needed sense.
        """
        sk = self.skeleton
        S = sk.mirror
        partner = list(range(len(sk)))
        for left, right in sk.pairs:
            a, b = sk.index(left), sk.index(right)
            partner[a], partner[b] = b, a
        new_angles = np.empty_like(self.joint_angles)
        for j, joint in enumerate(sk.joints):
            p = sk.joints[partner[j]]
            if p.ndof != joint.ndof:
                raise SkeletonError(f"cannot mirror: {joint.name!r} and {p.name!r} have "
                                    "different DOF counts")
            if joint.ndof == 0:
                continue
            if not np.allclose(S @ p.pre @ S, joint.pre, atol=1e-6):
                raise SkeletonError(f"cannot mirror: fixed rotations of {joint.name!r} and "
                                    f"{p.name!r} are not mirror images")
            signs = np.einsum("ij,kj,ki->k", S, p.axes, joint.axes)
            if not np.allclose(np.abs(signs), 1.0, atol=1e-6):
                raise SkeletonError(f"cannot mirror: DOF axes of {joint.name!r} and "
                                    f"{p.name!r} are not mirror images")
            new_angles[:, sk.dof_slice(j)] = -signs * self.joint_angles[:, sk.dof_slice(partner[j])]
        root_signs = np.einsum("ij,kj,ki->k", S, sk.root_axes, sk.root_axes)
        if not np.allclose(np.abs(root_signs), 1.0, atol=1e-6):
            raise SkeletonError("cannot mirror: root axes are not symmetric under the mirror")
        meta = dict(self.meta)
        meta["mirrored"] = not meta.get("mirrored", False)
        return self.replace(root_translation=self.root_translation @ S.T,
                            root_rotation=-root_signs * self.root_rotation,
                            joint_angles=new_angles, meta=meta)


def concatenate(motions: list[Motion], name: str | None = None) -> Motion:
    """Join motions of the same skeleton and frame rate end to end (no blending)."""
    if not motions:
        raise ValueError("concatenate needs at least one motion")
    first = motions[0]
    for m in motions[1:]:
        if m.skeleton is not first.skeleton and m.skeleton.dof_names != first.skeleton.dof_names:
            raise SkeletonError("cannot concatenate motions of different skeletons")
        if abs(m.fps - first.fps) > 1e-9:
            raise ValueError(f"cannot concatenate motions at {first.fps} and {m.fps} fps")
    return first.replace(
        root_translation=np.concatenate([m.root_translation for m in motions]),
        root_rotation=np.concatenate([m.root_rotation for m in motions]),
        joint_angles=np.concatenate([m.joint_angles for m in motions]),
        name=name or first.name)

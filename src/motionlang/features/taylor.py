"""Features of Taylor, Hinton & Roweis (2006) for the CRBM (CMU ASF/AMC motions).

Per frame, at 30 Hz (120 Hz capture, every 4th frame):

* the root as 6 numbers (see ``features.root``): ground-plane step in the heading frame
  of the previous frame (sideways x, forward z; metres/frame), heading change (rad/frame),
  root height (m), absolute pitch and roll (rad; ``Ry(yaw) Rx(pitch) Rz(roll)`` in the
  Y-up frame);
* every joint with DOFs as the exponential map (axis * angle, radians, 3 numbers) of its
  DOF rotation ``chain(axes, angles)`` (the ASF ``C``/``C^T`` frame change excluded).

Dimensions that never change in the training data (e.g. two of the three exp-map numbers of
a one-DOF bone, or the components of a bone that never moves) are dropped; their values are
remembered and restored by ``decode``. The rest are z-normalised.

``decode`` integrates heading and steps from ``start = (x0, z0, yaw0)`` (default: origin,
yaw 0); :meth:`TaylorFeatures.start` gives a motion's own placement.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features import root as rootlib
from motionlang.features.base import FeatureSet, as_numpy, downsample
from motionlang.features.normalizer import Normalizer
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import (
    chain,
    expmap_to_matrix,
    matrix_to_chain,
    matrix_to_expmap,
)
from motionlang.kinematics.skeleton import Skeleton

ROOT_NAMES = ("root_vx", "root_vz", "root_dyaw", "root_height", "root_pitch", "root_roll")


@dataclass
class TaylorConfig:
    """Options of :class:`TaylorFeatures`.

    Attributes:
        fps: frame rate of the sequences (30 Hz in the paper).
        const_tol: a dimension whose standard deviation over the training data is below
            this is dropped as constant.
        dtype: numpy dtype of ``encode``'s output.
    """

    fps: float = 30.0
    const_tol: float = 1e-8
    dtype: str = "float32"


def _dof_joints(skeleton: Skeleton) -> list[int]:
    return [j for j, joint in enumerate(skeleton.joints) if joint.ndof > 0]


class TaylorFeatures(FeatureSet):
    """Root trajectory + per-bone exp-maps, constants dropped; ``encode`` -> (T, D) at 30 Hz."""

    kind = "taylor"
    Config = TaylorConfig

    def __init__(self, config: TaylorConfig | None = None, **options):
        super().__init__(config, **options)
        self.skeleton: Skeleton | None = None   # the fitted skeleton (not serialised)
        self.joints: list[str] = []              # names of the joints with DOFs
        self.keep: np.ndarray | None = None      # (D_all,) bool, dims kept
        self.const: np.ndarray | None = None     # (D_all,) values used for dropped dims

    # ------------------------------------------------------------------ layout
    @property
    def all_names(self) -> list[str]:
        """Names of all dims before constant ones are dropped."""
        return list(ROOT_NAMES) + [f"{j}_r{c}" for j in self.joints for c in "xyz"]

    @property
    def names(self) -> list[str]:
        if self.keep is None:
            raise MotionlangError("TaylorFeatures is not fitted (call fit or load)")
        return [n for n, k in zip(self.all_names, self.keep) if k]

    def _check_skeleton(self, skeleton: Skeleton) -> None:
        have = [skeleton.joints[j].name for j in _dof_joints(skeleton)]
        if have != self.joints:
            raise SkeletonError(f"skeleton {skeleton.name!r} does not match the fitted one "
                                f"(joints with DOFs differ)")

    # ------------------------------------------------------------------ raw features
    def _raw(self, motion: Motion) -> np.ndarray:
        """(T, D_all) un-normalised features of a motion already at ``fps``."""
        sk = motion.skeleton
        tr = rootlib.root_trajectory(motion)
        parts = [tr["v"], tr["dyaw"][:, None], tr["height"][:, None], tr["pitch"][:, None],
                 tr["roll"][:, None]]
        for j in _dof_joints(sk):
            R = chain(sk.joints[j].axes, motion.joint_angles[:, sk.dof_slice(j)])
            parts.append(matrix_to_expmap(R))
        return np.concatenate(parts, axis=1)

    # ------------------------------------------------------------------ API
    def fit(self, motions: Iterable[Motion]) -> TaylorFeatures:
        """Find constant dims and fit the normaliser; all motions share one skeleton layout."""
        motions = list(motions)
        if not motions:
            raise MotionlangError("TaylorFeatures.fit: no motions")
        self.skeleton = motions[0].skeleton
        self.joints = [self.skeleton.joints[j].name for j in _dof_joints(self.skeleton)]
        for m in motions[1:]:
            self._check_skeleton(m.skeleton)
        raw = np.concatenate([self._raw(downsample(m, self.fps)) for m in motions])
        self.keep = raw.std(axis=0) >= self.config.const_tol
        self.const = np.where(self.keep, 0.0, raw.mean(axis=0))
        self.normalizer = Normalizer(names=self.names).fit(raw[:, self.keep])
        return self

    def encode(self, motion: Motion) -> np.ndarray:
        """Motion (fitted skeleton layout, any fps) -> (T, D) normalised features at ``fps``."""
        self._require_fit()
        self._check_skeleton(motion.skeleton)
        raw = self._raw(downsample(motion, self.fps))
        return self._out(self.normalizer.transform(raw[:, self.keep]))

    def start(self, motion: Motion) -> np.ndarray:
        """(x0, z0, yaw0) of the motion's first frame."""
        return rootlib.root_trajectory(motion[:1])["start"]

    def decode(self, features, skeleton: Skeleton | None = None, start=(0.0, 0.0, 0.0),
               name: str = "decoded") -> Motion:
        """Features (T, D) -> :class:`Motion` at ``fps`` on ``skeleton`` (default: the
        fitted one; required after ``load``, which does not store skeletons)."""
        self._require_fit()
        sk = skeleton if skeleton is not None else self.skeleton
        if sk is None:
            raise MotionlangError("TaylorFeatures.decode needs a skeleton (none was fitted "
                                  "in this session)")
        self._check_skeleton(sk)
        f = as_numpy(features)
        if f.ndim != 2 or f.shape[1] != self.dim:
            raise MotionlangError(f"Taylor features must be (T, {self.dim}), got {f.shape}")
        raw = np.tile(self.const, (len(f), 1))
        raw[:, self.keep] = self.normalizer.inverse(f)
        traj = {"v": raw[:, 0:2], "dyaw": raw[:, 2], "height": raw[:, 3], "pitch": raw[:, 4],
                "roll": raw[:, 5]}
        trans, rot = rootlib.trajectory_to_root(traj, sk, start)
        angles = np.zeros((len(f), sk.ndof))
        for k, j in enumerate(_dof_joints(sk)):
            joint = sk.joints[j]
            r = raw[:, 6 + 3 * k: 9 + 3 * k]
            if joint.ndof == 1:
                # one axis a: R = rot(a, t) has exp-map t a (|t| <= pi), so t = r . a exactly,
                # whatever the axis (matrix_to_chain needs coordinate axes)
                angles[:, sk.dof_slice(j)] = r @ joint.axes[0][:, None]
            else:
                angles[:, sk.dof_slice(j)] = matrix_to_chain(expmap_to_matrix(r), joint.axes)
        return Motion(sk, self.fps, trans, rot, angles, name=name,
                      source_format="amc" if sk.name.startswith("cmu") else "synthetic",
                      meta={"decoded_from": self.kind})

    # ------------------------------------------------------------------ persistence
    def _state(self) -> dict:
        return {"joints": self.joints, "keep": [bool(k) for k in self.keep],
                "const": [float(c) for c in self.const]}

    def _set_state(self, state: dict) -> None:
        self.joints = list(state["joints"])
        self.keep = np.asarray(state["keep"], dtype=bool)
        self.const = np.asarray(state["const"], dtype=float)

"""Joint-angle features of Plappert, Mandery & Asfour (2018) for MMM (KIT) motions.

A frame is the 44 MMM joint angles (radians, in ``MMM_DOF_ORDER``) plus, by default, the
root pose, each dimension z-normalised, plus a binary "active" flag (1 while the motion
runs, 0 on padding; it is not normalised, so a decoder can be trained to switch it off
to end a motion). Motions are down-sampled from 100 Hz to 10 Hz; the 10 possible start
offsets give 10 sequences per motion (``encode_all``), the paper's data augmentation.

Choice made here for the root: Plappert et al. feed the root pose along with the joint
angles. Its absolute position and heading depend on where in the capture room the subject
stood, so we feed it in a translation- and heading-invariant form (``root="trajectory"``,
6 dims, the Taylor et al. 2006 parametrisation, see ``features.root``): ground-plane step
in the heading frame (sideways, forward; metres/frame), heading change (rad/frame), root
height (m), pitch and roll (rad). ``root="none"`` gives the 44-angle variant, decoded
with the root standing still at the training data's mean height.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features import root as rootlib
from motionlang.features.base import FeatureSet, as_numpy, downsample
from motionlang.features.normalizer import Normalizer
from motionlang.formats.mmm_model import MMM_DOF_ORDER, mmm_height, mmm_skeleton
from motionlang.kinematics.motion import Motion

ROOT_NAMES = ("root_vx", "root_vz", "root_dyaw", "root_height", "root_pitch", "root_roll")


def mmm_columns(skeleton) -> np.ndarray:
    """(44,) column of each ``MMM_DOF_ORDER`` DOF in ``Motion.joint_angles``.

    Raises:
        SkeletonError: the skeleton lacks some of the 44 MMM DOFs.
    """
    names = skeleton.dof_names
    missing = [n for n in MMM_DOF_ORDER if n not in names]
    if missing:
        raise SkeletonError(f"angles features need an MMM skeleton; {skeleton.name!r} lacks "
                            f"DOFs {missing[:5]}{'...' if len(missing) > 5 else ''} (models on "
                            "'positions' features read any rig that maps onto the 21-joint "
                            "body)")
    return np.array([names.index(n) for n in MMM_DOF_ORDER])


@dataclass
class AnglesConfig:
    """Options of :class:`AnglesFeatures`.

    Attributes:
        fps: frame rate of the sequences (10 Hz in the paper).
        root: ``"trajectory"`` (6 root dims) or ``"none"``.
        active: append the binary active flag as the last dimension.
        dtype: numpy dtype of ``encode``'s output.
    """

    fps: float = 10.0
    root: str = "trajectory"
    active: bool = True
    dtype: str = "float32"

    def __post_init__(self):
        if self.root not in ("trajectory", "none"):
            raise ValueError(f"root must be 'trajectory' or 'none', got {self.root!r}")


class AnglesFeatures(FeatureSet):
    """MMM joint angles (+ root trajectory) + active flag; ``encode`` -> (T, D) at 10 Hz."""

    kind = "angles"
    Config = AnglesConfig

    def __init__(self, config: AnglesConfig | None = None, **options):
        super().__init__(config, **options)
        self.subject_height = 1.75   # m, mean over the fitted motions (for decoding)
        self.rest_height = 1.0       # m, mean root height (decoding with root="none")

    # ------------------------------------------------------------------ layout
    @property
    def names(self) -> list[str]:
        n = list(MMM_DOF_ORDER)
        if self.config.root == "trajectory":
            n += ROOT_NAMES
        return n + (["active"] if self.config.active else [])

    @property
    def n_normalised(self) -> int:
        """Dimensions that go through the normaliser (all but the active flag)."""
        return self.dim - int(self.config.active)

    def n_offsets(self, motion: Motion) -> int:
        """How many distinct down-sampled sequences a motion gives (100 / 10 Hz -> 10)."""
        step = motion.fps / self.fps
        n = int(round(step)) if abs(step - round(step)) < 1e-9 and step >= 1 else 1
        return min(n, motion.n_frames)  # a 3-frame motion has only 3 non-empty offsets

    # ------------------------------------------------------------------ raw features
    def _raw(self, motion: Motion) -> np.ndarray:
        """Un-normalised (T, n_normalised) features of a motion already at ``self.fps``."""
        parts = [motion.joint_angles[:, mmm_columns(motion.skeleton)]]
        if self.config.root == "trajectory":
            tr = rootlib.root_trajectory(motion)
            parts += [tr["v"], tr["dyaw"][:, None], tr["height"][:, None],
                      tr["pitch"][:, None], tr["roll"][:, None]]
        return np.concatenate(parts, axis=1)

    # ------------------------------------------------------------------ API
    def fit(self, motions: Iterable[Motion]) -> AnglesFeatures:
        """Fit the normaliser on every offset sequence of ``motions`` (MMM motions)."""
        motions = list(motions)
        if not motions:
            raise MotionlangError("AnglesFeatures.fit: no motions")
        raws = [self._raw(downsample(m, self.fps, o))
                for m in motions for o in range(self.n_offsets(m))]
        self.normalizer = Normalizer(names=self.names[:self.n_normalised]).fit(raws)
        self.subject_height = float(np.mean([m.meta.get("height", 1.75) for m in motions]))
        self.rest_height = float(np.mean(np.concatenate(
            [rootlib.root_pose(m)[0][:, 1] for m in motions])))
        return self

    def encode(self, motion: Motion, offset: int = 0) -> np.ndarray:
        """(T', D) features of ``motion[offset::step]`` (step = motion.fps / fps)."""
        self._require_fit()
        x = self.normalizer.transform(self._raw(downsample(motion, self.fps, offset)))
        if self.config.active:
            x = np.concatenate([x, np.ones((len(x), 1))], axis=1)
        return self._out(x)

    def encode_all(self, motion: Motion) -> list[np.ndarray]:
        """One (T'_k, D) array per start offset k = 0 .. n_offsets-1 (augmentation)."""
        return [self.encode(motion, k) for k in range(self.n_offsets(motion))]

    def n_active(self, features) -> int:
        """Frames before the active flag first drops below 0.5 (at least 1)."""
        f = as_numpy(features)
        if not self.config.active:
            return len(f)
        off = np.flatnonzero(f[:, -1] < 0.5)
        return max(1, int(off[0]) if len(off) else len(f))

    def decode(self, features, skeleton=None, start=(0.0, 0.0, 0.0),
               name: str = "decoded") -> Motion:
        """Features (T, D) -> MMM :class:`Motion` at ``fps``.

        Frames from the first one whose active flag is below 0.5 are dropped (at least one
        frame is kept). ``skeleton`` defaults to ``mmm_skeleton(mean fitted height)``;
        ``start`` (x0, z0, yaw0) places frame 0 (default: origin, yaw 0).
        """
        self._require_fit()
        f = as_numpy(features)
        if f.ndim != 2 or f.shape[1] != self.dim:
            raise MotionlangError(f"angles features must be (T, {self.dim}), got {f.shape}")
        f = f[:self.n_active(f)]
        raw = self.normalizer.inverse(f[:, :self.n_normalised])
        sk = skeleton if skeleton is not None else mmm_skeleton(self.subject_height)
        T = len(raw)
        angles = np.zeros((T, sk.ndof))
        angles[:, mmm_columns(sk)] = raw[:, :44]
        if self.config.root == "trajectory":
            r = raw[:, 44:50]
            traj = {"v": r[:, 0:2], "dyaw": r[:, 2], "height": r[:, 3], "pitch": r[:, 4],
                    "roll": r[:, 5]}
            trans, rot = rootlib.trajectory_to_root(traj, sk, start)
        else:
            x0, z0, yaw0 = start
            p = np.tile([x0, self.rest_height, z0], (T, 1))
            ypr = np.tile([yaw0, 0.0, 0.0], (T, 1))
            trans, rot = rootlib.root_dofs(p, ypr, sk)
        return Motion(sk, self.fps, trans, rot, angles, name=name, source_format="mmm",
                      meta={"height": mmm_height(sk), "decoded_from": self.kind})

    # ------------------------------------------------------------------ persistence
    def _state(self) -> dict:
        return {"subject_height": self.subject_height, "rest_height": self.rest_height}

    def _set_state(self, state: dict) -> None:
        self.subject_height = float(state.get("subject_height", 1.75))
        self.rest_height = float(state.get("rest_height", 1.0))

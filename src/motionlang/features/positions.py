"""Joint-position features of Ghosh et al. (2021) (two-stream text-to-motion on KIT-ML).

Per frame at 12.5 Hz: the 21 KIT joints (``joint_map.KIT21_NAMES``) in the body's local
frame — origin at the root projected on the ground, Y up, the body facing +Z — as 63
numbers (joint-major x, y, z; the root's own local y is the root height, its local x and
z are always 0), followed by the root's global trajectory: ground-plane step in the body
frame of the previous frame (sideways x, forward z; metres/frame) and heading change
(rad/frame). 66 dimensions, z-normalised (constant ones only centred).

Facing direction: the horizontal perpendicular to the left->right hips + shoulders line,
``forward = up x ((RH - LH) + (RS - LS))``, as usual for joint-position data.

The inverse (:meth:`PositionFeatures.decode`) integrates heading and steps and returns
global positions (T, 21, 3). Frame 0 is placed at ``start = (x0, z0, yaw0)``; by default at
the origin facing +Z. :meth:`PositionFeatures.start` gives a motion's own placement, so
``decode(encode(m), start=start(m))`` reproduces :meth:`PositionFeatures.body` (``positions21``
moved vertically so that the feet stand on y = 0) exactly.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features import root as rootlib
from motionlang.features.base import FeatureSet, as_numpy, downsample
from motionlang.features.joint_map import KIT21_NAMES, positions21
from motionlang.features.normalizer import Normalizer
from motionlang.kinematics.motion import Motion

_I = {n: i for i, n in enumerate(KIT21_NAMES)}

#: frame rate of the features unless configured (Ghosh et al. 2021: KIT-ML at 12.5 Hz)
DEFAULT_FPS = 12.5
#: values a frame: the local joints (x, y, z each), then the root's step (2) and turn (1)
N_LOCAL = 3 * len(KIT21_NAMES)
DIM = N_LOCAL + 3


@dataclass
class PositionsConfig:
    """Options of :class:`PositionFeatures`.

    Attributes:
        fps: frame rate of the sequences (12.5 Hz in Ghosh et al. 2021).
        joint_map: a key of ``joint_map.JOINT_MAPS``, or None: the map a motion carries in
            ``meta["joint_map"]``, else one picked from its joint names.
        dtype: numpy dtype of ``encode``'s output.
        floor: move each motion vertically so that its feet stand on y = 0
            (:func:`floor_height`), whatever floor height the source file uses. Checkpoints
            written before this option existed read back with it off.
    """

    fps: float = DEFAULT_FPS
    joint_map: str | None = None
    dtype: str = "float32"
    floor: bool = True


#: the six foot joints of the 21-joint body (ankles, mid-feet, toes)
FOOT = tuple(KIT21_NAMES.index(n) for n in ("LA", "LMrot", "LF", "RA", "RMrot", "RF"))


def floor_height(p21: np.ndarray) -> float:
    """Height of the floor under a motion (T, 21, 3): the 5th percentile over frames of the
    lowest foot joint. A percentile, not the minimum, so that one glitched frame of a real
    capture cannot sink the whole motion; jumps and lifted feet do not raise it as long as
    one foot is down in more than 5 % of the frames."""
    lowest = p21[:, FOOT, 1].min(axis=1)
    return float(np.percentile(lowest, 5.0))


def facing_yaw(p21: np.ndarray) -> np.ndarray:
    """(T, 21, 3) canonical positions -> (T,) heading, radians about +Y (0 = facing +Z)."""
    across = (p21[:, _I["RH"]] - p21[:, _I["LH"]]) + (p21[:, _I["RS"]] - p21[:, _I["LS"]])
    forward = np.cross(np.array([0.0, 1.0, 0.0]), across)
    return np.arctan2(forward[:, 0], forward[:, 2])


def split_global(p21: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Global (T, 21, 3) -> local (T, 21, 3), steps v (T, 2), dyaw (T,), start (3,)."""
    yaw = facing_yaw(p21)
    ground = p21[:, 0, [0, 2]]
    origin = np.stack([ground[:, 0], np.zeros(len(p21)), ground[:, 1]], axis=1)
    local = rootlib.to_heading(p21 - origin[:, None], yaw[:, None])
    v, dyaw = rootlib.increments(ground, yaw)
    return local, v, dyaw, np.array([ground[0, 0], ground[0, 1], yaw[0]])


def local_joints(raw):
    """Un-normalised rows (..., DIM) -> the local joints (..., 21, 3): numpy or torch, a view
    where the array library gives one."""
    return raw[..., :N_LOCAL].reshape(*raw.shape[:-1], len(KIT21_NAMES), 3)


def root_step(raw):
    """Un-normalised rows (..., DIM) -> the root's ground step (..., 2): sideways, forward,
    metres/frame, in the previous frame's heading frame (numpy or torch)."""
    return raw[..., N_LOCAL:N_LOCAL + 2]


def root_turn(raw):
    """Un-normalised rows (..., DIM) -> the heading change (...,), rad/frame."""
    return raw[..., N_LOCAL + 2]


def positions_to_rows(p21: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Global (T, 21, 3) metres -> un-normalised rows (T, DIM) as they stand (no floor
    shift, no resampling) and the placement of frame 0 (3,) (``x0, z0, yaw0``)."""
    local, v, dyaw, start = split_global(p21)
    return np.concatenate([local.reshape(len(p21), -1), v, dyaw[:, None]], axis=1), start


def join_global(local: np.ndarray, v: np.ndarray, dyaw: np.ndarray,
                start=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Inverse of :func:`split_global` -> global (T, 21, 3) metres."""
    ground, yaw = rootlib.integrate(v, dyaw, start)
    origin = np.stack([ground[:, 0], np.zeros(len(yaw)), ground[:, 1]], axis=1)
    return rootlib.from_heading(local, yaw[:, None]) + origin[:, None]


class PositionFeatures(FeatureSet):
    """Local 21-joint positions + root trajectory; ``encode`` -> (T, 66) at 12.5 Hz."""

    kind = "positions"
    encodes_rows = True
    Config = PositionsConfig

    @property
    def names(self) -> list[str]:
        return [f"{j}_{c}" for j in KIT21_NAMES for c in "xyz"] + [
            "root_vx", "root_vz", "root_dyaw"]

    def body(self, motion: Motion) -> np.ndarray:
        """(T, 21, 3) metres at ``fps``: the global positions these features describe
        (``positions21``, moved onto the floor when ``config.floor``)."""
        p = positions21(downsample(motion, self.fps), self.config.joint_map)
        if self.config.floor:
            p = p - np.array([0.0, floor_height(p), 0.0])
        return p

    def _raw(self, motion: Motion) -> tuple[np.ndarray, np.ndarray]:
        """-> un-normalised (T, 66) of ``motion`` at ``fps``, and its start (3,)."""
        return positions_to_rows(self.body(motion))

    def fit(self, motions: Iterable[Motion]) -> PositionFeatures:
        """Fit the normaliser on the (T, 66) raw features of ``motions`` (any mappable
        skeleton: MMM, CMU-ASF, BVH)."""
        return self.fit_rows([self._raw(m)[0] for m in motions])

    def rows(self, motion: Motion) -> np.ndarray:
        """(T, 66) un-normalised features of ``motion`` at ``fps``."""
        return self._raw(motion)[0]

    def fit_rows(self, rows: Sequence[np.ndarray]) -> PositionFeatures:
        """Fit the normaliser on motions' :meth:`rows`."""
        if not rows:
            raise MotionlangError("PositionFeatures.fit: no motions")
        self.normalizer = Normalizer(names=self.names).fit(list(rows))
        return self

    def encode_rows(self, rows: np.ndarray) -> np.ndarray:
        """A motion's :meth:`rows` -> (T, 66) normalised features (what :meth:`encode` gives)."""
        self._require_fit()
        return self._out(self.normalizer.transform(rows))

    @classmethod
    def from_dict(cls, d: dict) -> PositionFeatures:
        # files from before the floor option: it was off
        d = {**d, "config": {"floor": False, **d.get("config", {})}}
        return super().from_dict(d)

    def encode(self, motion: Motion) -> np.ndarray:
        """Motion (any supported skeleton, any fps) -> (T, 66) normalised features."""
        return self.encode_rows(self._raw(motion)[0])

    def encode_positions(self, p21) -> np.ndarray:
        """Global positions (T, 21, 3) metres, already at ``fps``, -> (T, 66) normalised
        features, the body taken as it stands (no floor shift: ``body`` does that for a
        ``Motion``). Frame 0's placement is dropped, as in :meth:`encode`."""
        self._require_fit()
        p = np.asarray(p21, dtype=np.float64)
        if p.ndim != 3 or p.shape[1:] != (len(KIT21_NAMES), 3) or not len(p):
            raise MotionlangError(f"positions must be (T >= 1, {len(KIT21_NAMES)}, 3), got "
                                  f"{p.shape}")
        return self._out(self.normalizer.transform(positions_to_rows(p)[0]))

    def start(self, motion: Motion) -> np.ndarray:
        """(x0, z0, yaw0) of the motion's first frame: root on the ground plane, heading."""
        return self._raw(motion)[1]

    def decode(self, features, start=(0.0, 0.0, 0.0), *, pin_root: bool = False
               ) -> np.ndarray:
        """Features (T, 66) -> global joint positions (T, 21, 3) metres, Y up.

        Not a :class:`Motion`: positions carry no joint rotations (that would need inverse
        kinematics). Frame 0 is placed at ``start`` (x0, z0, yaw0). ``pin_root``: set the
        root's local x and z to 0 first, as they are by construction (a model's frames only
        approximate these constant columns, and would otherwise move the root off the path).
        """
        self._require_fit()
        f = as_numpy(features)
        if f.ndim != 2 or f.shape[1] != self.dim:
            raise MotionlangError(f"position features must be (T, {self.dim}), got {f.shape}")
        raw = self.normalizer.inverse(f)
        if pin_root:
            raw[:, [3 * _I["root"], 3 * _I["root"] + 2]] = 0.0
        return join_global(local_joints(raw), root_step(raw), root_turn(raw), start)

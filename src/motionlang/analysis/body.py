"""The body the detectors read: 21 joints on the floor at one analysis rate, with the signals
every detector shares computed once, all in body units.

Every threshold of :mod:`motionlang.analysis` is in leg lengths (hip to ankle, ``L``), the
body's stature or seconds, never in metres or frames, so that a child and an adult, a file in
centimetres and one in inches, 30 Hz and 120 Hz compare alike. The positions are resampled to
about :data:`RATE` frames a second (every n-th frame, n chosen from the file's rate): the
fastest action read here (a punch, a clap) lasts a tenth of a second and more, and a 10-minute
120 Hz take then stays cheap.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.ndimage import percentile_filter, uniform_filter1d

from motionlang.analysis.evidence import clean_mask
from motionlang.errors import MotionlangError
from motionlang.features.body21 import leg_length21, normalise21, stature21
from motionlang.features.joint_map import KIT21_NAMES, bone_lengths21
from motionlang.features.positions import facing_yaw

#: frames a second the detectors work at (at least; a slower file keeps its own rate)
RATE = 30.0
#: seconds of the light smoothing applied before anything is read (marker jitter)
SMOOTH = 0.07
#: the local floor's window, seconds: longer than any flight, short enough for a ramp
FLOOR_WINDOW = 1.5
#: seconds over which horizontal speeds are taken (a stride's half-cycle and more)
SPEED_SPAN = 0.5
#: a foot whose lowest joint is within this (leg lengths) of the local floor and moves
#: slower than :data:`CONTACT_SPEED` carries weight (``features.gait``'s values)
CONTACT_HEIGHT = 0.1
CONTACT_SPEED = 1.3
#: a lowest foot whose slowest joint moves slower than this (leg lengths a second, in 3D)
#: for :data:`SUPPORT_HOLD` s stands on something: the floor is there, whatever the floor
#: of the frames around it (the top of a box before the jump down from it); a flight's
#: apex is still for far less than that
SUPPORT_SPEED = 0.3
SUPPORT_HOLD = 0.15
#: leg lengths both wrists are above the head by when the hands may carry the body (a bar,
#: the rungs above, a climbing frame)
HANDS_OVERHEAD = 0.1
#: seconds a foot is held still, while the hands are overhead, before it is taken to stand
#: on something: a hanging body's legs swing and pause at each end of the swing for less,
#: a foot on a rung stands there while the other climbs
HANGING_HOLD = 0.3
#: seconds both gripping hands may move at once (one takes over from the other)
GRIP_GAP = 0.3

J = {n: i for i, n in enumerate(KIT21_NAMES)}
FOOT_JOINTS = ((J["LA"], J["LMrot"], J["LF"]), (J["RA"], J["RMrot"], J["RF"]))
SIDES = ("left", "right")
#: (shoulder, elbow, wrist) and (hip, knee, ankle), left then right
ARMS = ((J["LS"], J["LE"], J["LW"]), (J["RS"], J["RE"], J["RW"]))
LEGS = ((J["LH"], J["LK"], J["LA"]), (J["RH"], J["RK"], J["RA"]))
MIN_FRAMES = 2
#: a frame where the median joint leaves the path its neighbours' steps predict by more than
#: this (leg lengths) is a splice: two recordings end to end, or a capture glitch; a body
#: moves smoothly, and no action bends every joint's path that far within one frame
SPLICE = 0.08
#: seconds of the shortest piece between splices read on its own (about a stride); a shorter
#: one is read with the piece after it (the last, with the one before)
MIN_PIECE = 1.0


def pieces(p21, fps: float) -> list[tuple[int, int]]:
    """The continuous pieces of a take: (start, end) frames (end exclusive), cut after each
    frame where the path of the median joint breaks by more than :data:`SPLICE` leg lengths,
    a piece shorter than :data:`MIN_PIECE` s joined to its neighbour; ``[(0, T)]`` for a take
    without a splice.

    The break at frame i is the step from i to i + 1 less the mean of the steps on either
    side: for a smooth path, nearly nothing at any frame rate; at a splice, the jump itself.
    """
    p = np.asarray(p21, dtype=np.float64)
    whole = [(0, len(p) if p.ndim else 0)]
    if p.ndim != 3 or p.shape[1:] != (len(KIT21_NAMES), 3) or len(p) < 4 or \
            not np.isfinite(p).all():
        return whole   # Body.from_positions says what is wrong
    leg = leg_length21(bone_lengths21(p))
    if not (np.isfinite(leg) and leg > 1e-9):
        return whole
    d = np.diff(p, axis=0)
    g = np.zeros(len(d))
    g[1:-1] = np.median(np.linalg.norm(d[1:-1] - 0.5 * (d[:-2] + d[2:]), axis=-1),
                        axis=1) / leg
    # one break spreads to the frames either side at half its size: its peak is the cut
    peak = (g > SPLICE) & (g >= np.roll(g, 1)) & (g >= np.roll(g, -1))
    inner = [int(i) + 1 for i in np.flatnonzero(peak)]
    # a frame or two off the path and back is a glitch: no cut at all
    glitch = {x for c, d in zip(inner, inner[1:]) if d - c <= 2 for x in (c, d)}
    cuts = [0] + [c for c in inner if c not in glitch] + [len(p)]
    short = MIN_PIECE * fps
    if len(cuts) - 2 > len(p) / short:   # breaks everywhere: no smooth piece to read apart
        return whole
    strength = [np.inf] + [float(g[c - 1]) for c in cuts[1:-1]] + [np.inf]
    # a piece too short to read goes with its neighbour across the weaker of its two cuts
    while len(cuts) > 2:
        k = int(np.argmin(np.diff(cuts)))
        if cuts[k + 1] - cuts[k] >= short:
            break
        drop = k if strength[k] < strength[k + 1] else k + 1
        del cuts[drop], strength[drop]
    return list(zip(cuts, cuts[1:]))


def _odd(n: float) -> int:
    return max(1, int(round(n)) | 1)


@dataclass(frozen=True, eq=False)
class Body:
    """A motion as the detectors read it.

    Attributes:
        p: (T, 21, 3) metres, Y up, floor at y = 0, frame 0 facing +Z, at :attr:`fps`.
        fps: the analysis rate (frames a second).
        leg: leg length (hip-knee-ankle), metres.
        stature: standing height, metres (``features.body21.stature21``).
    """

    p: np.ndarray
    fps: float
    leg: float
    stature: float

    @classmethod
    def from_positions(cls, p21, fps: float) -> Body:
        """(T, 21, 3) Y-up positions of any unit at ``fps`` -> a :class:`Body`.

        Raises:
            MotionlangError: wrong shape, non-finite values, no body (legs of no length).
        """
        p = np.asarray(p21, dtype=np.float64)
        if p.ndim != 3 or p.shape[1:] != (len(KIT21_NAMES), 3):
            raise MotionlangError(f"analysis: positions must be (T, 21, 3), got {p.shape}")
        if not (np.isfinite(fps) and fps > 0):
            raise MotionlangError(f"analysis: the frame rate must be a positive number, "
                                  f"got {fps}")
        if len(p) < MIN_FRAMES:
            raise MotionlangError(f"analysis: the motion has {len(p)} frame(s); at least "
                                  f"{MIN_FRAMES} are needed to see any movement")
        if not np.isfinite(p).all():
            raise MotionlangError("analysis: positions are not all finite")
        step = max(1, int(round(fps / RATE)))
        if len(p[::step]) < MIN_FRAMES:    # too few frames to thin: all of them
            step = 1
        p = p[::step]
        fps = fps / step
        leg = leg_length21(bone_lengths21(p))
        if not (np.isfinite(leg) and leg > 1e-9):
            raise MotionlangError("analysis: the body's legs have no length (all joints at "
                                  "one point?)")
        p = normalise21(p)
        if len(p) >= 3:
            p = uniform_filter1d(p, _odd(SMOOTH * fps), axis=0, mode="nearest")
        stature = stature21(p)
        return cls(p=p, fps=float(fps), leg=float(leg), stature=float(stature))

    # ------------------------------------------------------------------ basics
    @property
    def n(self) -> int:
        return len(self.p)

    @property
    def duration(self) -> float:
        return self.n / self.fps

    def t(self, i: int) -> float:
        """Seconds of frame ``i``."""
        return i / self.fps

    def frames(self, seconds: float) -> int:
        """A span in seconds as a whole number of frames (at least 1)."""
        return max(1, int(round(seconds * self.fps)))

    def joint(self, name: str) -> np.ndarray:
        """(T, 3) one joint's path."""
        return self.p[:, J[name]]

    def speed_of(self, x: np.ndarray) -> np.ndarray:
        """(T, k) positions -> (T,) speed, metres a second (central differences)."""
        if len(x) < 2:
            return np.zeros(len(x))
        return np.linalg.norm(np.gradient(x, axis=0), axis=-1) * self.fps

    # ------------------------------------------------------------------ shared signals
    @cached_property
    def yaw(self) -> np.ndarray:
        """(T,) facing, radians about +Y, unwrapped (positive turns are to the left)."""
        return np.unwrap(facing_yaw(self.p))

    @cached_property
    def forward(self) -> np.ndarray:
        """(T, 2) unit facing direction in the (x, z) ground plane."""
        return np.stack([np.sin(self.yaw), np.cos(self.yaw)], axis=1)

    @cached_property
    def ground_velocity(self) -> np.ndarray:
        """(T, 2) the root's horizontal velocity, m/s, over :data:`SPEED_SPAN` spans."""
        root = self.p[:, 0, [0, 2]]
        k = self.frames(SPEED_SPAN / 2)
        i = np.arange(self.n)
        hi, lo = np.clip(i + k, 0, self.n - 1), np.clip(i - k, 0, self.n - 1)
        return (root[hi] - root[lo]) * self.fps / np.maximum(hi - lo, 1)[:, None]

    @cached_property
    def ground_speed(self) -> np.ndarray:
        """(T,) horizontal root speed in leg lengths a second."""
        return np.linalg.norm(self.ground_velocity, axis=1) / self.leg

    @cached_property
    def foot_low(self) -> np.ndarray:
        """(2, T) height of each foot's lowest joint, metres."""
        return np.stack([self.p[:, list(f), 1].min(axis=1) for f in FOOT_JOINTS])

    @cached_property
    def local_floor(self) -> np.ndarray:
        """(T,) the floor under the body, metres: a rolling low percentile of the lowest foot
        over :data:`FLOOR_WINDOW` s, so that ramps, steps and drifting captures carry it."""
        # a window longer than the take is the whole take (and costs no more)
        size = _odd(min(FLOOR_WINDOW * self.fps, 2 * self.n + 1))
        low = self.foot_low.min(axis=0)
        floor = percentile_filter(low, 5, size=size, mode="nearest")
        # the window's low percentile reaches a lower floor before the feet do: where the
        # lowest foot is held still above it, it stands on that higher support
        speed = self.foot_speed3d[np.argmin(self.foot_low, axis=0), np.arange(self.n)]
        held = clean_mask(speed < SUPPORT_SPEED, self.fps, min_len=SUPPORT_HOLD, max_gap=0.0)
        floor = np.where(held & (low > floor), low, floor)
        # hands that grip something overhead may carry the body: the feet hang in the air
        # there, and the window's low percentile would follow them up; the floor is only
        # where a foot stands still, and holds where the body left it in between (never
        # above the feet: a body held by its hands may be lowered, or let go)
        stands = clean_mask(speed < SUPPORT_SPEED, self.fps, min_len=HANGING_HOLD, max_gap=0.0)
        known = ~self.gripping | stands
        if known.any() and not known.all():
            idx = np.flatnonzero(known)
            last = idx[np.clip(np.searchsorted(idx, np.arange(self.n), side="right") - 1,
                               0, None)]
            floor = np.where(known, floor, np.minimum(floor[last], low))
        return floor

    @cached_property
    def hands_overhead(self) -> np.ndarray:
        """(T,) bool: both wrists above the head by :data:`HANDS_OVERHEAD` leg lengths."""
        head = self.p[:, J["BUN"], 1]
        return np.asarray(np.stack([self.p[:, w, 1] - head > HANDS_OVERHEAD * self.leg
                                    for _, _, w in ARMS]).all(axis=0))

    @cached_property
    def gripping(self) -> np.ndarray:
        """(T,) bool: both hands overhead and one of them still in the world (slower than
        :data:`SUPPORT_SPEED`; both may move for :data:`GRIP_GAP` s), as on a bar, a rung or
        a frame; arms raised while walking, running or dancing go with the body."""
        if self.n < 2:
            return np.zeros(self.n, dtype=bool)
        wrists = [w for _, _, w in ARMS]
        speed = np.linalg.norm(np.gradient(self.p[:, wrists], axis=0), axis=-1).min(axis=1)
        speed = uniform_filter1d(speed * self.fps, _odd(0.1 * self.fps), mode="nearest")
        # hand over hand, the holding hand changes: both move for a moment
        return clean_mask(self.hands_overhead & (speed / self.leg < SUPPORT_SPEED), self.fps,
                          min_len=0.0, max_gap=GRIP_GAP) & self.hands_overhead

    @cached_property
    def foot_speed3d(self) -> np.ndarray:
        """(2, T) speed of each foot's slowest joint in 3D, leg lengths a second."""
        if self.n < 2:
            return np.zeros((2, self.n))
        out = [np.linalg.norm(np.gradient(self.p[:, list(f)], axis=0), axis=-1).min(axis=1)
               for f in FOOT_JOINTS]
        return uniform_filter1d(np.stack(out) * self.fps, _odd(0.1 * self.fps), axis=1,
                                mode="nearest") / self.leg

    @cached_property
    def foot_speed(self) -> np.ndarray:
        """(2, T) horizontal speed of each foot's slowest joint, leg lengths a second."""
        out = []
        for f in FOOT_JOINTS:
            v = np.gradient(self.p[:, list(f)][:, :, [0, 2]], axis=0) * self.fps if \
                self.n > 1 else np.zeros((self.n, 3, 2))
            out.append(np.linalg.norm(v, axis=-1).min(axis=1))
        return uniform_filter1d(np.stack(out), _odd(0.1 * self.fps), axis=1,
                                mode="nearest") / self.leg

    @cached_property
    def contacts(self) -> np.ndarray:
        """(2, T) bool: each foot carries weight (near the local floor and nearly still)."""
        near = self.foot_low - self.local_floor[None] < CONTACT_HEIGHT * self.leg
        return near & (self.foot_speed < CONTACT_SPEED)

    @cached_property
    def standing_pelvis(self) -> float:
        """Pelvis height above the floor of this body standing upright, metres: the legs
        straight under it (leg length) plus the ankle's height over the sole."""
        ankle = np.median(self.p[:, [J["LA"], J["RA"]], 1] - self.foot_low.T, axis=0).mean()
        return float(self.leg + max(ankle, 0.0))

    @cached_property
    def pelvis_height(self) -> np.ndarray:
        """(T,) pelvis over the local floor, in standing pelvis heights (1 = upright)."""
        return (self.p[:, 0, 1] - self.local_floor) / self.standing_pelvis

    @cached_property
    def trunk_tilt(self) -> np.ndarray:
        """(T,) angle of pelvis-to-neck from the vertical, degrees (0 upright, 90 level)."""
        v = self.p[:, J["BLN"]] - self.p[:, 0]
        n = np.linalg.norm(v, axis=1)
        return np.degrees(np.arccos(np.clip(v[:, 1] / np.maximum(n, 1e-9), -1.0, 1.0)))

    @cached_property
    def chest_normal(self) -> np.ndarray:
        """(T, 3) unit vector out of the chest (the way the torso faces, tilt included)."""
        across = (self.p[:, J["RS"]] - self.p[:, J["LS"]]) + (self.p[:, J["RH"]] -
                                                              self.p[:, J["LH"]])
        up = self.p[:, J["BLN"]] - self.p[:, 0]
        f = np.cross(up, across)
        return f / np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-9)

    @cached_property
    def _arm_lengths(self) -> tuple[float, float]:
        out = []
        for s, e, w in ARMS:
            b = [np.median(np.linalg.norm(self.p[:, a] - self.p[:, c], axis=1))
                 for a, c in ((s, e), (e, w))]
            out.append(float(sum(b)))
        return out[0], out[1]

    def arm_length(self, side: int) -> float:
        """Upper arm plus forearm of ``side`` (0 left, 1 right), metres (medians)."""
        return self._arm_lengths[side]

    def to_body_frame(self, v: np.ndarray) -> np.ndarray:
        """(T, 3) world vectors -> (T, 3) in the body's heading frame: x to the body's
        left, y up, z forward."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        x = c * v[:, 0] - s * v[:, 2]
        z = s * v[:, 0] + c * v[:, 2]
        return np.stack([x, v[:, 1], z], axis=1)

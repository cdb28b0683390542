"""What the feet say: walking, running or jumping, from foot contacts on the 21-joint body.

A description model learns which sentence goes with which features; on motion recorded
elsewhere (another body, speed, floor, rig) it can name the wrong gait, calling a brisk walk a
run. The gait itself is physics, the same in every lab (Alexander 1989, "Optimization and
gaits in the locomotion of vertebrates"): **walking** keeps a foot on the ground at every
moment and has double support, both feet down, at each step; **running** has a flight
phase, no foot down, between alternate single-foot stances, and no double support; a
**jump** leaves the ground from both feet at once (the flight starts right after both feet
were down), where a running stride leaves from one; a leap from one foot is a jump too when
its flight outlasts any running stride's.

Contacts (:func:`foot_contacts`): a foot is down when its lowest joint (ankle, heel or toe)
is within ``height`` leg lengths of the *local* floor and the foot moves slower than
``speed`` leg lengths a second. The local floor is a rolling low percentile of the lowest foot
joint over ``floor_window`` seconds, not one height for the whole take: real captures drift
upwards or downwards by centimetres over a few seconds (an uneven floor, a ramp, calibration),
enough to lift a planted foot above a fixed threshold and turn a walk's every step into a
flight. Thresholds scale with the leg, so that bodies of any size and any unit compare alike.

:func:`gait` sums a motion up (:class:`Gait`): its speed, Froude number, the shares of the
travelling frames in flight and double support, the two-footed jumps, and the action the
contacts show, or ``None`` when they show none clearly (standing, gestures, dance, turning in
place, a take too short).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import percentile_filter, uniform_filter1d

from motionlang.errors import MotionlangError
from motionlang.features.body21 import leg_length21
from motionlang.features.joint_map import KIT21_NAMES, bone_lengths21

#: the joints of each foot, left then right: ankle, heel (MMM's ``*Mrot``) and toe
FEET = tuple(tuple(KIT21_NAMES.index(side + n) for n in ("A", "Mrot", "F")) for side in "LR")
GRAVITY = 9.81  # m/s^2

# Thresholds, in leg lengths (hip to ankle) and seconds. A planted foot of a walk or a run
# stays within a few centimetres of the floor and nearly still; swing feet move at several
# leg lengths a second.
CONTACT_HEIGHT = 0.1      # leg lengths above the local floor (9 cm on a 0.87 m leg)
CONTACT_SPEED = 1.3       # leg lengths / s
FLOOR_WINDOW = 1.5        # s: the local floor's window (longer than a jump's flight)
FOOT_OFFSET = 0.1         # leg lengths: most one foot's floor may lie above the other's
TRAVEL_SPEED = 0.5        # leg lengths / s: slower than this is not locomotion
JUMP_FLIGHT = 0.12        # s: shortest flight counted as a jump
JUMP_TAKEOFF = 0.08       # s: both feet down within this before a jump's flight
LEAP_FLIGHT = 0.35        # s: a flight this long is a jump from any take-off (a leap): longer
                          # than any running stride's


@dataclass(frozen=True)
class Gait:
    """A motion's gait summary.

    Attributes:
        speed: median horizontal speed of the root over the travelling frames (all frames
            when none travels), m/s, from 0.5 s spans.
        froude: ``speed ** 2 / (g * leg)``; people change from walking to running near 0.5.
        travelling: share of frames in which the root moves faster than ``TRAVEL_SPEED``.
        flight: share of the travelling frames with no foot down.
        double: share of the travelling frames with both feet down.
        bounce: :func:`vault_bounce` (NaN for a take under a second).
        jumps: flights of at least ``JUMP_FLIGHT`` s that start from both feet, or of at
            least ``LEAP_FLIGHT`` s from one (leaps), within the take.
        run_score: :func:`_run_score`, above 0 running, below walking (-3..3).
        action: ``"jump"`` (two-footed take-offs, at least one per 10 s), else ``"run"`` or
            ``"walk"`` (by ``run_score``) for locomotion (travelling in at least 40 % of the
            frames and a second), else None: standing, gestures, turning on the spot.
    """

    speed: float
    froude: float
    travelling: float
    flight: float
    double: float
    bounce: float
    jumps: int
    run_score: float
    action: str | None


def _check(p21, fps: float) -> np.ndarray:
    p = np.asarray(p21, dtype=np.float64)
    if p.ndim != 3 or p.shape[1:] != (len(KIT21_NAMES), 3):
        raise MotionlangError(f"gait: positions must be (T, 21, 3), got {p.shape}")
    if not (np.isfinite(fps) and fps > 0):
        raise MotionlangError(f"gait: fps must be a positive number, got {fps}")
    if not np.isfinite(p).all():
        raise MotionlangError("gait: positions are not all finite")
    return p


def _odd(n: float) -> int:
    return max(1, int(round(n)) | 1)


def foot_contacts(p21, fps: float, *, height: float = CONTACT_HEIGHT,
                  speed: float = CONTACT_SPEED, floor_window: float = FLOOR_WINDOW
                  ) -> np.ndarray:
    """(T, 21, 3) Y-up positions (any unit) at ``fps`` -> (2, T) bool: left and right foot
    down at each frame (module docstring; thresholds in leg lengths and seconds)."""
    p = _check(p21, fps)
    leg = leg_length21(bone_lengths21(p))
    if not leg > 0:
        raise MotionlangError("gait: the legs have no length")
    lowest = np.stack([p[:, list(f), 1].min(axis=1) for f in FEET])          # (2, T)
    size = _odd(floor_window * fps)
    common = percentile_filter(lowest.min(axis=0), 5, size=size, mode="nearest")
    # each foot's own floor, at most FOOT_OFFSET above the common one: rigs and marker sets
    # put one sole a few centimetres above the other, and a sloping floor does the same
    own = np.stack([percentile_filter(low, 5, size=size, mode="nearest") for low in lowest])
    floor = np.minimum(own, common + FOOT_OFFSET * leg)
    # foot speed: the slowest of its joints (a rolling foot pivots on heel or toe), smoothed
    # over ~0.05 s so that 120 Hz marker noise does not break a contact
    vel = np.gradient(p[:, :, [0, 2]], axis=0) * fps                       # (T, 21, 2)
    v = np.stack([np.linalg.norm(vel[:, list(f)], axis=-1).min(axis=1) for f in FEET])
    v = uniform_filter1d(v, _odd(0.05 * fps), axis=1, mode="nearest")
    return (lowest - floor < height * leg) & (v < speed * leg)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[(first, end), ...] half-open runs of True in a 1-D bool array."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def gait(p21, fps: float) -> Gait:
    """Sum up a motion's gait (:class:`Gait`) from (T, 21, 3) Y-up positions at ``fps``."""
    p = _check(p21, fps)
    leg = leg_length21(bone_lengths21(p))
    down = foot_contacts(p, fps)
    T = len(p)
    k = max(1, int(round(0.5 * fps)))
    root = p[:, 0, [0, 2]]
    if T > k:
        span = np.linalg.norm(root[k:] - root[:-k], axis=-1) * fps / k      # (T - k,)
        sp = np.concatenate([span, np.full(k, span[-1])])
    else:
        sp = np.zeros(T)
    travelling = sp > TRAVEL_SPEED * leg
    # the speed of the travel itself: standing before and after does not slow a run down
    speed = float(np.median(sp[travelling] if travelling.any() else sp))
    none = ~down[0] & ~down[1]
    both = down[0] & down[1]
    n_trav = int(travelling.sum())
    flight = float(none[travelling].mean()) if n_trav else 0.0
    double = float(both[travelling].mean()) if n_trav else 0.0
    jumps = 0
    before = _odd(JUMP_TAKEOFF * fps)
    for a, b in _runs(none):
        two_footed = a > 0 and both[max(0, a - before):a].any()
        if (b - a) / fps >= (JUMP_FLIGHT if two_footed else LEAP_FLIGHT) and 0 < a and b < T:
            jumps += 1
    bounce = vault_bounce(p, fps)
    score = _run_score(flight, double, bounce, speed ** 2 / (GRAVITY * leg))
    action: str | None = None
    locomotion = n_trav / fps >= 1.0 and n_trav >= 0.4 * T
    if jumps >= max(1.0, 0.1 * T / fps) and not (locomotion and score > 0):
        action = "jump"     # two-footed take-offs in good number, and not a run's strides
    elif locomotion:
        action = "run" if score > 0 else "walk"
    return Gait(speed=speed, froude=speed ** 2 / (GRAVITY * leg), travelling=n_trav / T,
                flight=flight, double=double, bounce=bounce, jumps=jumps, run_score=score,
                action=action)


def _run_score(flight: float, double: float, bounce: float, froude: float) -> float:
    """-3..3: above 0 the gait is running, below walking; the sum of three cues, each in
    -1..1, so that no single one (a contact threshold on a sloping floor, a bouncy walker,
    a slow jogger) decides alone: flight minus double support, the vault-or-bounce
    correlation (:func:`vault_bounce`), and the Froude number against 0.5, where people
    change gait (log2 scale, so 0.25 and 1.0 are the ends)."""
    contacts = np.clip((flight - double - 0.03) / 0.1, -1.0, 1.0)
    vault = 0.0 if np.isnan(bounce) else np.clip(bounce / 0.3, -1.0, 1.0)
    speed = np.clip(np.log2(max(froude, 1e-6) / 0.5), -1.0, 1.0)
    return float(contacts + vault + speed)


def vault_bounce(p21, fps: float) -> float:
    """Correlation (-1..1) of the root's height with the feet's horizontal spread, both with
    their slow trend removed: walking vaults over a stiff leg, so the root is highest when
    the feet pass each other and lowest when they are spread (negative); running bounces
    on a compressed leg, lowest at mid-stance and highest in flight with the legs split
    (positive). NaN for a motion shorter than a second."""
    p = _check(p21, fps)
    k = _odd(fps)
    if len(p) < 1.2 * k:
        return float("nan")
    def hp(x):
        return x - uniform_filter1d(x, k, mode="nearest")
    la, ra = KIT21_NAMES.index("LA"), KIT21_NAMES.index("RA")
    y = hp(p[:, 0, 1])
    spread = hp(np.linalg.norm(p[:, la, [0, 2]] - p[:, ra, [0, 2]], axis=-1))
    edge = k // 3
    y, spread = y[edge:len(y) - edge], spread[edge:len(y) - edge]
    if y.std() < 1e-9 or spread.std() < 1e-9:
        return float("nan")
    return float(np.corrcoef(y, spread)[0, 1])

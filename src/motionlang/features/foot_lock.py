"""Foot contact clean-up for generated 21-joint motion: planted feet stay where they land.

A text-to-motion model predicts every frame's pose and the root's velocity separately, so a
foot that should stand on the floor drifts with the root's small errors (a generated foot
slides several times as fast as a real take's while down; the figures of every step below are
in ``docs/results/real-motion.md``). :func:`lock_feet` is the usual post-process of animation
pipelines (as in Kovar, Schreiner & Gleicher 2002, "Footskate cleanup": move the root so the
planted feet can stay, then the legs by IK), done on positions:

0. **root**: over every frame step on which a foot is down (step 1's contacts), the whole
   body is moved back horizontally by that foot's step (by the mean step when both are down),
   the correction smoothed over ``window`` seconds so that the root's speed does not jump
   where a contact begins or ends. A body that drifts or slides while its feet are down then
   stands on them; a body in the air keeps its own path. It changes travel where the model's
   stance feet slide: a body whose stance feet slide backwards travels further, one whose
   feet slide forwards less, and real takes a little less (their own small slides). A foot
   dragged along the floor (slower than ``speed``) is a contact here too: the body stops with
   it. (The lock alone could not hold the two-stream model's drifting standing gestures: the
   leg would have to reach too far.)
1. **contact**: a foot is down at frame t when its toe is below ``height`` m above the floor
   and moves slower than ``speed`` m/s (central difference); runs of at least ``min_frames``
   such frames are the contacts (the thresholds of
   ``evaluation.metrics.physics.foot_skating``; it measures frame steps, this looks at
   frames, so a step into a contact can still count as a slide there). A contact whose toe
   would have to be pulled more than ``max_shift`` m to its mean, or whose held ankle the
   leg could not reach, is a glide, not a plant (a foot dragged along while the body
   travels): it is left as decoded, since holding it would stretch the leg out behind the
   body. (Step 0 has already moved the body with such a foot: what is left to hold is the
   foot's slide against its own hip. Holding every contact, leg or not, brings a model's
   skating down to the real takes', but stretches legs out straight, e.g. for "a person
   kicks" from a Bandai pose.)
2. **lock**: during a contact the whole foot (ankle, mid-foot, toe) is moved horizontally so
   that its toe stays at the contact's mean toe position; over ``blend`` frames either side
   the shift fades linearly to zero (or to the next contact's), so the foot does not pop; a
   contact within ``blend`` frames of either end of the motion holds to that end.
3. **leg**: on the frames whose foot moved, the knee is placed again by two-bone IK from the
   unchanged hip to the moved ankle, keeping the frame's own thigh and shank lengths and
   bending on the original knee's side (forward, from the hips' facing, where the leg was
   straight); an ankle out of the leg's reach is pulled back to 99.9 % of it (the foot with
   it: that contact slides by what is left). Frames without a shift are left as they are.
4. **floor**: a foot whose lowest joint (ankle, mid-foot or toe) is below the floor is
   raised until it is on it, by the same IK (the hip stays, the knee bends a little more);
   the lift fades in and out linearly over ``blend`` frames either side, so the foot does
   not pop. (A generated standing gesture can keep its toes under the floor for most of its
   frames, where the real takes' joints hardly ever go under it.) Other joints below the
   floor (a hand on the ground), a collapsed leg and an ankle the leg cannot reach stay where
   they are.

Apart from step 0's horizontal move of the whole body, the hips, trunk and arms are
untouched.
"""
from __future__ import annotations

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES

_I = KIT21_NAMES.index
#: (hip, knee, ankle, mid-foot, toe) of each leg, left then right
LEGS = tuple(tuple(_I(side + j) for j in ("H", "K", "A", "Mrot", "F")) for side in "LR")


def _checked(p21, fps: float, what: str) -> np.ndarray:
    """A float64 copy of positions (T, 21, 3); bad shapes or rates are one-line errors."""
    p = np.array(p21, dtype=np.float64)
    if p.ndim != 3 or p.shape[1:] != (21, 3):
        raise MotionlangError(f"{what}: positions must be (T, 21, 3), got {p.shape}")
    if not fps > 0:
        raise MotionlangError(f"{what}: fps must be positive, got {fps}")
    return p


def contacts(toe: np.ndarray, fps: float, *, height: float = 0.05, speed: float = 1.0,
             floor: float = 0.0, min_frames: int = 2) -> list[tuple[int, int]]:
    """``[(first, last), ...]`` frame runs (inclusive) where the toe ``(T, 3)`` (metres, Y
    up) is down: below ``height`` above ``floor`` and slower than ``speed`` m/s, for at
    least ``min_frames`` frames."""
    toe = np.asarray(toe, dtype=np.float64)
    xz = toe[:, [0, 2]]
    if len(toe) < 2:
        return []
    v = np.linalg.norm(np.gradient(xz, axis=0), axis=-1) * fps          # (T,) m/s
    down = (toe[:, 1] - floor < height) & (v < speed)
    runs, start = [], None
    for t, d in enumerate(np.append(down, False)):
        if d and start is None:
            start = t
        elif not d and start is not None:
            if t - start >= min_frames:
                runs.append((start, t - 1))
            start = None
    return runs


def _held_at(xz: np.ndarray, pinned: np.ndarray | None) -> np.ndarray:
    """Where a contact's toe (n, 2) is held: its mean over the contact's pinned frames
    (n,) bool where it has any, else over all of them."""
    if pinned is not None and pinned.any():
        return np.asarray(xz[pinned].mean(axis=0))
    return np.asarray(xz.mean(axis=0))


def _shifts(toe_xz: np.ndarray, runs: list[tuple[int, int]], blend: int,
            pinned: np.ndarray | None = None) -> np.ndarray:
    """(T, 2) horizontal shift of the foot: inside a run the shift that holds the toe where
    :func:`_held_at` says, zero farther than ``blend`` frames from every run, linear in
    between."""
    T = len(toe_xz)
    shift = np.zeros((T, 2))
    if not runs:
        return shift
    known = np.zeros(T, dtype=bool)
    for a, b in runs:
        at = _held_at(toe_xz[a:b + 1], None if pinned is None else pinned[a:b + 1])
        shift[a:b + 1] = at - toe_xz[a:b + 1]
        known[a:b + 1] = True
    idx = np.arange(T)
    near = np.full(T, np.inf)
    for a, b in runs:
        near = np.minimum(near, np.maximum(0, np.maximum(a - idx, idx - b)))
    known |= near > blend            # far from every contact: shift 0 (already)
    for k in range(2):
        shift[~known, k] = np.interp(idx[~known], idx[known], shift[known, k])
    return shift


def anchor_root(p21, fps: float, *, height: float = 0.05, speed: float = 1.0,
                floor: float = 0.0, min_frames: int = 2, window: float = 0.4) -> np.ndarray:
    """Global 21-joint positions (T, 21, 3) metres, Y up, at ``fps`` Hz -> the same motion
    moved horizontally, frame by frame as a whole, so that feet that are down stay put (step
    0 of the module docstring); a new array.

    On each frame step (t, t + 1) inside a contact (:func:`contacts`, with ``height`` /
    ``speed`` / ``floor`` / ``min_frames``) the body is moved back by the down toe's step,
    by the mean of both toes' where both are down; these corrections are averaged over a
    centred box of ``2 * (round(window * fps) // 2) + 1`` frame steps (5 for 0.4 s at 12.5
    Hz; 1, no smoothing, below 1.5 frames; near either end, over the steps there are), and
    summed from frame 0, which stays. Toe steps outside contacts are not read (a NaN there
    stays in its own frames).
    """
    p = _checked(p21, fps, "anchor_root")
    T = len(p)
    if T < 2:
        return p
    toes = [leg[4] for leg in LEGS]
    steps = np.diff(p[:, toes][..., [0, 2]], axis=0)                 # (T - 1, 2 toes, 2)
    down = np.zeros((T - 1, len(toes)))
    for k, toe in enumerate(toes):
        for a, b in contacts(p[:, toe], fps, height=height, speed=speed, floor=floor,
                             min_frames=min_frames):
            down[a:b, k] = 1.0                                       # steps a .. b - 1
    held = np.where(down[..., None] > 0, steps, 0.0).sum(axis=1)
    step = -held / np.maximum(down.sum(axis=1), 1)[:, None]           # (T - 1, 2)
    half = int(round(window * fps)) // 2
    if half > 0:
        # a box average over the steps there are: a steady drift is removed exactly up to
        # both ends; a contact within ``half`` steps of an end is corrected a little less
        # than in full, never more (repeating the end step instead over-corrected a
        # one-step contact there, the more so the higher the frame rate)
        box, n = np.ones(2 * half + 1), len(step)
        there = np.convolve(np.ones(n), box)[half:half + n]          # steps in each box
        step = np.stack([np.convolve(step[:, k], box)[half:half + n] / there
                         for k in range(2)], axis=-1)
    offset = np.concatenate([np.zeros((1, 2)), np.cumsum(step, axis=0)])   # (T, 2)
    p[:, :, 0] += offset[:, None, 0]
    p[:, :, 2] += offset[:, None, 1]
    return p


def _two_bone(hip: np.ndarray, knee: np.ndarray, ankle: np.ndarray, target: np.ndarray,
              forward: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knee and ankle (T, 3) for ankle ``target``: thigh and shank keep their per-frame
    lengths, the knee bends toward the original knee's side (toward ``forward`` (T, 3)
    where the original leg is straight within 1 cm); unreachable targets are pulled toward
    the hip to 99.9 % of the leg's length."""
    l1 = np.linalg.norm(knee - hip, axis=-1)
    l2 = np.linalg.norm(ankle - knee, axis=-1)
    d = target - hip
    dist = np.linalg.norm(d, axis=-1)
    reach = 0.999 * (l1 + l2)
    lo = np.abs(l1 - l2) + 1e-6
    clamped = np.clip(dist, lo, reach)
    u = d / np.maximum(dist, 1e-9)[:, None]
    target = hip + u * clamped[:, None]
    along = (l1 ** 2 - l2 ** 2 + clamped ** 2) / (2 * clamped)
    r = np.sqrt(np.maximum(l1 ** 2 - along ** 2, 0.0))
    # the bend side: the original knee's offset from the original hip-ankle line; a straight
    # original leg (within 1 cm) says nothing of it: knees bend forward
    u0 = ankle - hip
    u0 = u0 / np.maximum(np.linalg.norm(u0, axis=-1, keepdims=True), 1e-9)
    k = knee - hip
    side = k - (k * u0).sum(-1, keepdims=True) * u0
    side = np.where(np.linalg.norm(side, axis=-1, keepdims=True) < 0.01, forward, side)
    pole = side - (side * u).sum(-1, keepdims=True) * u
    pole = pole / np.maximum(np.linalg.norm(pole, axis=-1, keepdims=True), 1e-9)
    return hip + along[:, None] * u + r[:, None] * pole, target


def _holdable(p: np.ndarray, run: tuple[int, int], leg: tuple[int, int, int, int],
              max_shift: float, reach: float, pinned: np.ndarray | None = None) -> bool:
    """Whether a contact is a plant that can be held: no toe pulled more than ``max_shift``
    m to where it is held (:func:`_held_at`), and the held ankle within ``reach`` of the
    leg's length."""
    (a, b), (hip, knee, ankle, toe) = run, leg
    xz = p[a:b + 1, toe, [0, 2]]
    pull = _held_at(xz, None if pinned is None else pinned[a:b + 1]) - xz   # (n, 2)
    if np.linalg.norm(pull, axis=-1).max() > max_shift:
        return False
    held = p[a:b + 1, ankle].copy()
    held[:, [0, 2]] += pull
    length = (np.linalg.norm(p[a:b + 1, knee] - p[a:b + 1, hip], axis=-1)
              + np.linalg.norm(p[a:b + 1, ankle] - p[a:b + 1, knee], axis=-1))
    return bool((np.linalg.norm(held - p[a:b + 1, hip], axis=-1) <= reach * length).all())


def _floor_lift(depth: np.ndarray, blend: int) -> np.ndarray:
    """(T,) lift (m) for a foot ``depth`` (T,) m under the floor (0 where above): the depth
    itself on every sunk frame (the foot lands on the floor, not above it), and on the
    frames above the floor a linear fade to zero over ``blend`` frames from the nearby sunk
    frames (the largest where fades overlap), so the foot does not pop."""
    fade = np.zeros_like(depth)
    for k in range(1, blend + 1):
        f = depth * (1.0 - k / (blend + 1))
        fade[k:] = np.maximum(fade[k:], f[:-k])
        fade[:-k] = np.maximum(fade[:-k], f[k:])
    return np.where(depth > 0, depth, fade)


def _move_leg(p: np.ndarray, frames: np.ndarray, leg: tuple[int, ...], shift: np.ndarray,
              forward: np.ndarray) -> None:
    """Move the ankle of ``leg`` (hip, knee, ankle, mid, toe) by ``shift`` (n, 3) m on
    ``frames`` (n,), in place: the knee by two-bone IK from the unchanged hip, the mid-foot
    and toe with the ankle (by what the leg's reach allowed)."""
    hip, knee, ankle, mid, toe = leg
    new_knee, new_ankle = _two_bone(p[frames, hip], p[frames, knee], p[frames, ankle],
                                    p[frames, ankle] + shift, forward[frames])
    foot = new_ankle - p[frames, ankle]                 # the shift, less what was out of reach
    for j in (mid, toe):
        p[frames, j] += foot
    p[frames, knee], p[frames, ankle] = new_knee, new_ankle


def lock_feet(p21, fps: float, *, height: float = 0.05, speed: float = 1.0, floor: float = 0.0,
              blend: int = 2, min_frames: int = 2, max_shift: float = 0.15,
              reach: float = 1.0, anchor: bool = True, window: float = 0.4,
              pinned: np.ndarray | None = None) -> np.ndarray:
    """Global 21-joint positions (T, 21, 3) metres, Y up, at ``fps`` Hz -> the same motion
    moved so that its feet that are down stay put, with every foot contact held in place and
    every foot raised onto the floor where it sank under it (module docstring); a new array.

    ``height`` / ``speed`` / ``floor``: what counts as a foot down (:func:`contacts`);
    ``floor`` is also the height a sunk foot is raised to;
    ``blend``: frames over which a lock fades in and out; ``min_frames``: shortest contact;
    ``max_shift``: longest pull (m) of a toe to its contact's mean, beyond which the contact
    is a glide and left alone; ``reach``: the same where a held ankle would be farther from
    the hip than this fraction of the leg's length (thigh + shank); ``anchor``: step 0
    (:func:`anchor_root`, smoothed over ``window`` seconds) first, False leaves the root's
    path as the model made it. ``pinned``: frames (T,) bool where the feet already are
    where they must stay (the kept frames around an in-betweening gap): a contact that
    takes in some of them is held where its toe is on them, not at its mean.
    """
    p = _checked(p21, fps, "lock_feet")
    if anchor:
        p = anchor_root(p, fps, height=height, speed=speed, floor=floor,
                        min_frames=min_frames, window=window)
    # the body's forward direction: the hips' left-right axis turned about the vertical
    (lh, *_), (rh, *_) = LEGS
    across = p[:, lh] - p[:, rh]
    forward = np.stack([-across[:, 2], np.zeros(len(p)), across[:, 0]], axis=-1)
    for hip, knee, ankle, mid, toe in LEGS:
        leg = (np.linalg.norm(p[:, knee] - p[:, hip], axis=-1) > 1e-6) & \
              (np.linalg.norm(p[:, ankle] - p[:, knee], axis=-1) > 1e-6)   # a collapsed leg: left
        runs = contacts(p[:, toe], fps, height=height, speed=speed, floor=floor,
                        min_frames=min_frames)
        runs = [r for r in runs
                if _holdable(p, r, (hip, knee, ankle, toe), max_shift, reach, pinned)]
        if runs:
            s = _shifts(p[:, toe, [0, 2]], runs, blend, pinned)
            moved = np.flatnonzero((np.abs(s) > 0).any(axis=1) & leg)
            shift = np.zeros((len(moved), 3))
            shift[:, [0, 2]] = s[moved]
            _move_leg(p, moved, (hip, knee, ankle, mid, toe), shift, forward)
        depth = np.maximum(0.0, floor - p[:, [ankle, mid, toe], 1].min(axis=1))
        lift = _floor_lift(depth, blend)
        moved = np.flatnonzero((lift > 0) & leg)
        shift = np.zeros((len(moved), 3))
        shift[:, 1] = lift[moved]
        _move_leg(p, moved, (hip, knee, ankle, mid, toe), shift, forward)
    return p

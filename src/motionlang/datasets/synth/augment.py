"""Augmentation for any motion-language data (synthetic or real KIT-ML): left/right
mirroring with the matching word swap, speed change by resampling, concatenation.
"""
from __future__ import annotations

import re

import numpy as np

from motionlang.datasets.synth.grammar import sentences
from motionlang.datasets.synth.spec import LOCOMOTION, Primitive
from motionlang.kinematics.motion import Motion, concatenate
from motionlang.kinematics.rotations import axis_angle, chain, matrix_to_chain

# Word pairs swapped by mirroring. left/right, leftwards/rightwards and clockwise/
# counterclockwise swap both ways (mirroring twice restores the text); other spellings
# ("counter clockwise", "clock-wise", "anticlockwise", ...) map onto these canonical forms.
_BIJECTIVE = {"left": "right", "leftwards": "rightwards", "leftward": "rightward",
              "clockwise": "counterclockwise"}
_ONE_WAY = {"counter clockwise": "clockwise", "counter-clockwise": "clockwise",
            "counter clock-wise": "clockwise", "counter-clock-wise": "clockwise",
            "anticlockwise": "clockwise", "anti-clockwise": "clockwise",
            "clock-wise": "counterclockwise", "clock wise": "counterclockwise"}
_PAIRS = {**_BIJECTIVE, **{b: a for a, b in _BIJECTIVE.items()}, **_ONE_WAY}
_WORD = re.compile(r"(?<![\w-])(" + "|".join(sorted(map(re.escape, _PAIRS), key=len,
                                                     reverse=True)) + r")(?!\w)",
                   re.IGNORECASE)
_SPEED_WORD = re.compile(r"\b(slow|slowly|quick|quickly|fast|rapidly|briskly|hastily|"
                         r"leisurely|speed|pace)\b", re.IGNORECASE)
_SPEED_UP = {"slow": "normal", "normal": "fast", "fast": "fast"}
_SPEED_DOWN = {"fast": "normal", "normal": "slow", "slow": "slow"}


def _match_case(word: str, like: str) -> str:
    if like.isupper() and len(like) > 1:
        return word.upper()
    if like[:1].isupper():
        return word[:1].upper() + word[1:]
    return word


def mirror_text(sentence: str) -> str:
    """Swap left/right (and clockwise/counterclockwise), keeping capitalisation."""
    return _WORD.sub(lambda m: _match_case(_PAIRS[m.group(0).lower()], m.group(0)), sentence)


def mirror_primitive(p: Primitive) -> Primitive:
    q = Primitive.from_dict(p.to_dict())
    swap = {"left": "right", "right": "left"}
    q.side = swap.get(q.side, q.side)
    q.direction = swap.get(q.direction, q.direction)
    return q


def mirror_sample(motion: Motion, texts: list[str],
                  primitives: list[Primitive] | None = None):
    """Mirror a motion (``Motion.mirror``) with its sentences and ground truth.

    Returns:
        (mirrored motion, mirrored texts, mirrored primitives or None).
    """
    prims = None if primitives is None else [mirror_primitive(p) for p in primitives]
    return motion.mirror(), [mirror_text(t) for t in texts], prims


def change_speed(motion: Motion, factor: float, texts: list[str] | None = None,
                 primitives: list[Primitive] | None = None, rng=None):
    """Play ``motion`` ``factor`` times faster (resampled to the same frame rate).

    Text is only changed where the speed is known:

    * with ground truth ``primitives`` (synthetic data), walk/run speeds move one level
      (slow/normal/fast) when ``factor`` >= 1.25 or <= 0.8, frame ranges are rescaled and
      new sentences are written by the grammar (``rng`` needed);
    * without, texts that state a speed cannot stay true and make this return None;
      other texts are kept unchanged.

    Returns:
        (motion, texts, primitives), or None if the texts cannot be kept consistent.
    """
    if not (0.25 <= factor <= 4.0):
        raise ValueError(f"speed factor must be in [0.25, 4], got {factor}")
    fast = motion.replace(fps=motion.fps * factor).resample(motion.fps)
    fast.meta["speed_factor"] = motion.meta.get("speed_factor", 1.0) * factor
    if primitives is None:
        if texts and any(_SPEED_WORD.search(t) for t in texts) and abs(factor - 1) > 0.1:
            return None
        return fast, texts, None
    new = []
    for p in primitives:
        q = Primitive.from_dict(p.to_dict())
        q.start, q.end = int(round(p.start / factor)), int(round(p.end / factor))
        if q.action in LOCOMOTION and q.speed:
            if factor >= 1.25:
                q.speed = _SPEED_UP[q.speed]
            elif factor <= 0.8:
                q.speed = _SPEED_DOWN[q.speed]
        new.append(q)
    if texts is not None:
        rng = rng if rng is not None else np.random.default_rng(0)
        texts = [s for s, _ in sentences(new, rng, max(1, len(texts)))]
    return fast, texts, new


_SUBJECT = re.compile(r"^\s*(a person|someone|somebody|a human|the subject|the person|"
                      r"a man|a woman|the man|the woman|a persons?|person|human|subject)\s+",
                      re.IGNORECASE)


def join_texts(first: str, second: str) -> str:
    """"A person walks." + "Someone waves." -> "A person walks, then waves." """
    a = first.strip().rstrip(".")
    m = _SUBJECT.match(second)
    rest = second.strip().rstrip(".")
    if m:
        rest = second[m.end():].strip().rstrip(".")
    else:
        rest = rest[:1].lower() + rest[1:]
    return f"{a}, then {rest}."


def _size(skeleton) -> float:
    """Sum of bone lengths (m): a body-size measure for retargeting root paths."""
    return float(np.linalg.norm(skeleton.offsets, axis=1).sum())


def _heading_rotation(motion: Motion, frame: int) -> np.ndarray:
    """(3, 3) root orientation of one frame in the source frame."""
    return chain(motion.skeleton.root_axes, motion.root_rotation[frame])


def concat_samples(a: Motion, b: Motion, texts_a: list[str], texts_b: list[str],
                   prims_a: list[Primitive] | None = None,
                   prims_b: list[Primitive] | None = None, blend_s: float = 0.3):
    """Play ``b`` after ``a``: ``b`` is moved and turned to start where and how ``a`` ends
    (about the vertical axis; its root path scaled to ``a``'s body size), its first
    ``blend_s`` seconds of joint angles are eased in
    from ``a``'s last pose, and texts are joined pairwise ("..., then ...").

    Both motions need the same skeleton DOFs and frame rate; ``b`` takes ``a``'s skeleton.
    """
    sk = a.skeleton
    up = sk.world.T @ np.array([0.0, 1.0, 0.0])  # canonical Y-up in the source frame
    lateral = np.eye(3)[int(np.argmin(np.abs(sk.world.T @ np.array([0.0, 1.0, 0.0]))))]

    def yaw(R):  # heading angle of a fixed body axis about ``up``
        v = R @ lateral
        v = v - up * (v @ up)
        e1 = np.cross(up, lateral if abs(lateral @ up) < 0.9 else np.roll(lateral, 1))
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(up, e1)
        return np.arctan2(v @ e2, v @ e1)

    d = yaw(_heading_rotation(a, -1)) - yaw(_heading_rotation(b, 0))
    Rv = axis_angle(up, d)
    R_b = Rv @ chain(sk.root_axes, b.root_rotation)
    root_rot = np.unwrap(matrix_to_chain(R_b, sk.root_axes), axis=0)
    # b is played by a's body: scale its root path by the ratio of body sizes
    scale = _size(sk) / _size(b.skeleton)
    p = (b.root_translation - b.root_translation[0]) * scale
    p = p @ Rv.T
    p += a.root_translation[-1] - up * (a.root_translation[-1] @ up)
    p += up * (b.root_translation[0] @ up) * scale
    angles = b.joint_angles.copy()
    n = min(len(angles), max(1, int(round(blend_s * b.fps))))
    w = np.linspace(1.0, 0.0, n)[:, None]
    angles[:n] += (a.joint_angles[-1] - b.joint_angles[0]) * w
    b2 = b.replace(skeleton=sk, root_translation=p, root_rotation=root_rot,
                   joint_angles=angles)
    motion = concatenate([a, b2], name=f"{a.name}+{b.name}")
    k = min(len(texts_a), len(texts_b))
    texts = [join_texts(texts_a[i], texts_b[i]) for i in range(k)]
    prims = None
    if prims_a is not None and prims_b is not None:
        prims = [Primitive.from_dict(p.to_dict()) for p in prims_a]
        for q in prims_b:
            q2 = Primitive.from_dict(q.to_dict())
            q2.start += a.n_frames
            q2.end += a.n_frames
            prims.append(q2)
    return motion, texts, prims

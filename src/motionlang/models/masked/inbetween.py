"""The numpy side of in-betweening: which tokens a set of kept frames fixes, and how the
generated frames join the kept ones.

A token covers 4 frames; it is kept only when all of its frames are (a token half inside
a gap is regenerated). The decoder reproduces the kept tokens' frames only up to the
tokenizer's error and places them where the generated root path leads, so the result
takes the kept frames as they are and moves each generated stretch by an offset per joint
that goes linearly from the gap's start (the last kept frame before it) to its end (the
first kept frame after it): no jump at either side ("offset blending"; a gap that reaches
an end of the motion moves rigidly, see :func:`blend`). Of several drafts,
the one that arrives closest to the kept frames after each gap (:func:`arrival_miss`) needs
the least of that offset, and so slides least. The offset still moves planted feet with
the body; :func:`join` with ``foot_lock`` holds them again afterwards.
"""
from __future__ import annotations

import numpy as np

from motionlang.features.foot_lock import lock_feet
from motionlang.models.masked.config import DOWN

#: frames over which the pose part of a one-sided gap's offset fades out (:func:`blend`)
POSE_FADE = 6
#: how far past the leg's length (a fraction of it) a held ankle may be for :func:`join` to
#: hold the contact: a stance leg is nearly straight, so a pull of a centimetre or two puts
#: its ankle just out of reach, and the lock's default would leave the whole slide; held,
#: the IK stops the ankle at the leg's reach and the foot slides only by what is left
JOIN_REACH = 1.05


def kept_tokens(keep: np.ndarray) -> np.ndarray:
    """Kept frames (T,) bool -> kept tokens (ceil(T / 4),) bool (all 4 frames kept; the
    last token's missing frames count as kept)."""
    keep = np.asarray(keep, dtype=bool)
    pad = (-len(keep)) % DOWN
    full = np.concatenate([keep, np.ones(pad, dtype=bool) if len(keep) else keep[:0]])
    return np.asarray(full.reshape(-1, DOWN).all(1))


def gaps(keep: np.ndarray) -> list[tuple[int, int]]:
    """Kept frames (T,) bool -> the runs of frames not kept, ``[(start, end), ...]``
    (end exclusive)."""
    out, start = [], None
    for t, k in enumerate(np.asarray(keep, dtype=bool)):
        if not k and start is None:
            start = t
        elif k and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, len(keep)))
    return out


def blend(generated: np.ndarray, source: np.ndarray, keep: np.ndarray, *,
          fade: int = POSE_FADE) -> np.ndarray:
    """Generated (T, J, 3) and source (T, J, 3) positions, kept frames (T,) -> the source
    on kept frames, the generated frames elsewhere moved to meet the kept frames at both
    ends of each gap (see module docstring): by an offset per joint (kept frame minus
    generated frame there) going linearly from one side to the other. A gap that reaches
    an end of the motion has one side only: its root's ground-plane offset moves the whole
    body throughout, and what is left of it joint by joint (the pose and height the
    generated frame has differently) fades out over ``fade`` frames from that side, so that
    the body is not held in the kept frame's pose difference, bones stretched, to the end."""
    gen = np.asarray(generated, dtype=np.float64)
    src = np.asarray(source, dtype=np.float64)
    keep = np.asarray(keep, dtype=bool)
    out = np.where(keep[:, None, None], src, gen)
    for a, b in gaps(keep):
        if a == 0 and b == len(keep):
            continue   # nothing kept: the generated motion as it is
        t = np.arange(a, b)
        if a > 0 and b < len(keep):
            before, after = src[a - 1] - gen[a - 1], src[b] - gen[b]
            w = ((t - (a - 1)) / (b - a + 1.0))[:, None, None]
            out[a:b] = gen[a:b] + (1 - w) * before + w * after
            continue
        off, k = (src[a - 1] - gen[a - 1], t - (a - 1)) if a > 0 else (src[b] - gen[b], b - t)
        ground = off[0] * np.array([1.0, 0.0, 1.0])
        left = np.clip(1.0 - k / (fade + 1.0), 0.0, 1.0)[:, None, None]
        out[a:b] = gen[a:b] + ground + left * (off - ground)
    return out


def join(generated: np.ndarray, source: np.ndarray, keep: np.ndarray, fps: float, *,
         foot_lock: bool = False) -> np.ndarray:
    """A chosen draft (T, J, 3) joined to the kept frames (T,) of ``source``: :func:`blend`;
    with ``foot_lock``, the draft's planted feet held first (``features.foot_lock.
    lock_feet``), then, after the blend, held again where they are down with the root's
    path left as blended (the lock's root step would take back the blend's offset and miss
    the kept frames), and the kept frames put back exactly. Both locks hold a contact whose
    ankle is a little out of the leg's reach (:data:`JOIN_REACH`)."""
    if not foot_lock:
        return blend(generated, source, keep)
    keep = np.asarray(keep, dtype=bool)
    joined = blend(lock_feet(generated, fps, reach=JOIN_REACH), source, keep)
    # a contact across a gap's edge is held where the kept frames have the foot, so that
    # putting the kept frames back moves it little
    held = lock_feet(joined, fps, anchor=False, pinned=keep, reach=JOIN_REACH)
    return np.where(keep[:, None, None], np.asarray(source, dtype=np.float64), held)


def arrival_miss(generated: np.ndarray, source: np.ndarray, keep: np.ndarray) -> float:
    """How far a generated motion (T, J, 3) misses the kept frames of ``source`` across its
    gaps, in metres: per gap that has kept frames on both sides, the mean over joints of
    the change in the offset :func:`blend` would apply from the gap's start to its end (what
    the blend must spread over the gap, and so what planted feet would slide by), summed
    over the gaps. Tokens carry no absolute position, so a draft can take the gap at
    another pace than the motion and arrive elsewhere."""
    gen = np.asarray(generated, dtype=np.float64)
    src = np.asarray(source, dtype=np.float64)
    miss = 0.0
    for a, b in gaps(keep):
        if a > 0 and b < len(keep):
            change = (src[b] - gen[b]) - (src[a - 1] - gen[a - 1])
            miss += float(np.linalg.norm(change, axis=-1).mean())
    return miss


def linear_fill(source: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """The baseline: each gap filled by interpolating every joint linearly between the
    kept frames around it (held where the gap reaches an end)."""
    src = np.asarray(source, dtype=np.float64)
    keep = np.asarray(keep, dtype=bool)
    if not keep.any():
        return src.copy()
    t = np.arange(len(src))
    flat = src.reshape(len(src), -1)
    out = np.stack([np.interp(t, t[keep], flat[keep, k]) for k in range(flat.shape[1])], 1)
    return out.reshape(src.shape)

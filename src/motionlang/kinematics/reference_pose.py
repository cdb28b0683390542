"""The rig's reference pose that some exporters write before a take.

BVH conversions of the CMU trials for Second Life and MakeHuman begin with the skeleton in
its T-pose (arms out level, the body as wide as it is tall) and blend from it into the
capture's first pose within a few frames, far faster than a body moves. Those frames are
the exporter's, not the subject's: a render of them pops, a clip composed from the take's
start opens with a T-pose. :func:`leading_reference_frames` finds them from the joints'
positions alone, whatever the rig or its units:

- the first frame is spread like a T-pose: its horizontal extent at least
  :data:`T_SPREAD` of the body's height;
- the frames that follow move at least :data:`BLEND_RATIO` times faster than the body does
  over the next second (the median of its largest joint speed there), for less than
  :data:`MAX_BLEND` s, and the body is :data:`NARROWER` once they end.

The windows are seconds at the declared rate: a header that misstates it (MakeHuman's 25 Hz
for 120 Hz frames) makes a long blend look longer, which may then be kept.
"""
from __future__ import annotations

import numpy as np

from motionlang.kinematics.motion import Motion

#: horizontal extent of the first frame, in body heights, from which it is a T-pose
#: (arms level: about 1; standing with the arms down: 0.3-0.5)
#: and how much narrower the body must be once the blend ends
T_SPREAD = 0.75
NARROWER = 0.1
#: how much faster than the take's next second the blend out of it moves
BLEND_RATIO = 3.0
#: s: blends out of the reference pose are shorter than this
MAX_BLEND = 0.25
#: s of the take after the blend that give its own speed
AFTER = 1.0


def _spread(p: np.ndarray) -> np.ndarray:
    """(T,) horizontal extent of each frame of ``p`` (T, J, 3): the diagonal of the box
    the joints span in the floor plane."""
    return np.hypot(np.ptp(p[:, :, 0], axis=1), np.ptp(p[:, :, 2], axis=1))


def leading_reference_frames(motion: Motion) -> int:
    """How many frames at the start of ``motion`` are its rig's reference pose and the
    exporter's blend out of it (module docstring); 0 for a take that starts as captured."""
    lead = max(1, int(round(MAX_BLEND * motion.fps)))
    n = min(motion.n_frames, lead + int(round(AFTER * motion.fps)) + 1)
    if n < lead + 4:
        return 0
    p = motion[:n].positions()
    height = float(np.median(np.ptp(p[:, :, 1], axis=1)))
    if not height > 0:
        return 0
    spread = _spread(p) / height
    if spread[0] < T_SPREAD:
        return 0
    speed = np.linalg.norm(np.diff(p, axis=0), axis=2).max(axis=1)   # (n-1,) per frame
    k = 0
    while k < lead and k + 1 < len(speed):
        own = float(np.median(speed[k + 1:]))
        if speed[k] < BLEND_RATIO * max(own, 1e-9):
            break
        k += 1
    if k == 0 or k >= lead or spread[k] > spread[0] - NARROWER:
        return 0
    return k

"""The fill-in protocol of Taylor, Hinton & Roweis 2006 (sec. 5) on CMU subject 35.

The data is ``cmu35WalkJog.mat`` (62 AMC channels per frame, degrees, 30 Hz) with the
normalisation ``cmu35TaylorScaleBias.mat``. The scoring space, which reproduces the paper's
nearest-neighbour numbers to four digits:

* per frame 59 values: root position (channels 1-3), sin then cos of the root rotation
  (channels 4-6, degrees), and 50 joint channels wrapped as asin(sin(x)) in degrees;
* consecutive frames of a trial concatenated into pairs, (T-1, 118) rows;
* normalised as (x - bias) * scale, the 59-vector repeated for both halves;
* error = squared error summed over the erased rows and dimensions, divided by the
  number of erased dimensions per row.

Pure numpy; the methods themselves (CRBM, AR) live in ``motionlang.models``.
"""
from __future__ import annotations

import numpy as np

# the data and its 59-value frames live in datasets.cmu35 (the recipe reads them too)
from motionlang.datasets.cmu35 import JOG_TRIALS as JOG_TRIALS
from motionlang.datasets.cmu35 import JOINT_CHANNELS as JOINT_CHANNELS
from motionlang.datasets.cmu35 import TRAIN_TRIALS as TRAIN_TRIALS
from motionlang.datasets.cmu35 import Cmu35 as Cmu35
from motionlang.datasets.cmu35 import load_cmu35 as load_cmu35
from motionlang.datasets.cmu35 import taylor59 as taylor59

# Erased dimensions (0-based, of the 118-value pair rows) and the gap (0-based pair rows of
# the walking test trial): 1-based, dims 17-23 / 76-82 and 30-59 / 89-118, pairs 63-124.
ERASED = {
    "leg": np.r_[16:23, 75:82],
    "upper body": np.r_[29:59, 88:118],
}
GAP_START_PAIR = 62          # pairs 62.. (0-based) to the end of the trial are erased


def pair_rows(frames: np.ndarray) -> np.ndarray:
    """(T, K) -> (T-1, 2K): each frame next to its successor (within one trial)."""
    return np.hstack([frames[:-1], frames[1:]])


def score_space(frames59: np.ndarray, scale: np.ndarray, bias: np.ndarray) -> np.ndarray:
    """(T, 59) -> (T-1, 118) normalised pair rows, the space every method is scored in."""
    return (pair_rows(frames59) - np.tile(bias, 2)) * np.tile(scale, 2)


def fill_error(true_rows: np.ndarray, filled_rows: np.ndarray, dims: np.ndarray,
               rows: slice | np.ndarray) -> float:
    """The paper's measure: sum of squared errors over ``rows`` x ``dims`` / len(dims)."""
    diff = true_rows[rows][:, dims] - filled_rows[rows][:, dims]
    return float((diff ** 2).sum() / len(dims))


def nearest_neighbour_fill(train_rows: np.ndarray, rows: np.ndarray, dims: np.ndarray) -> np.ndarray:
    """For every row of ``rows`` (N, K), the training row (M, K) closest (Euclidean) on the
    dimensions not in ``dims`` supplies the values of ``dims``. Returns a filled copy."""
    known = np.setdiff1d(np.arange(rows.shape[1]), dims)
    a, b = rows[:, known], train_rows[:, known]
    d2 = (a ** 2).sum(1)[:, None] - 2 * a @ b.T + (b ** 2).sum(1)[None]
    out = rows.copy()
    out[:, dims] = train_rows[d2.argmin(axis=1)][:, dims]
    return out


def hold_last_fill(frames: np.ndarray, known: np.ndarray) -> np.ndarray:
    """(T, D) frames, (T, D) mask: every unknown entry takes the last value before it."""
    out = np.array(frames, dtype=np.float64)
    for t in range(1, len(out)):
        out[t] = np.where(known[t], out[t], out[t - 1])
    return out


def frame_mask(n_frames: int, gap_start: int, frame_dims: np.ndarray, n_dims: int) -> np.ndarray:
    """(T, D) known-mask with ``frame_dims`` unknown from frame ``gap_start`` to the end."""
    known = np.ones((n_frames, n_dims), dtype=bool)
    known[gap_start:, frame_dims] = False
    return known


def per_frame_dims(pair_dims: np.ndarray) -> np.ndarray:
    """The 59-space dimensions behind erased pair dimensions (both halves -> one set)."""
    return np.unique(np.asarray(pair_dims) % 59)

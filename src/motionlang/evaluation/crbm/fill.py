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

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from motionlang.errors import DatasetError

# 0-based channels (of 62) kept as wrapped joint angles: 1-based 7-38, 41-47, 49-50, 53-59, 61-62.
JOINT_CHANNELS = np.r_[6:38, 40:47, 48:50, 52:59, 60:62]
# Erased dimensions (0-based, of the 118-value pair rows) and the gap (0-based pair rows of
# the walking test trial): the 1-based dims 17-23 / 76-82 and 30-59 / 89-118, pairs 63-124.
ERASED = {
    "leg": np.r_[16:23, 75:82],
    "upper body": np.r_[29:59, 88:118],
}
GAP_START_PAIR = 62          # pairs 62.. (0-based) to the end of the trial are erased
JOG_TRIALS = set(range(17, 27))  # CMU 35_17 - 35_26 are jogs; the others walks
TRAIN_TRIALS = [f"35_{i:02d}" for i in [*range(1, 18), *range(19, 27), 28, *range(30, 35)]]


@dataclass
class Cmu35:
    """The 31 training trials and the two test trials, raw channels (T_i, 62) in degrees."""
    train: list[np.ndarray]
    train_names: list[str]
    test: dict[str, np.ndarray]          # "35_18" (jog), "35_29" (walk)
    scale: np.ndarray                    # (59,)
    bias: np.ndarray                     # (59,)
    fps: float = 30.0
    labels: dict[str, str] = field(default_factory=dict)   # trial -> "walk" / "jog"


def _split(Y: np.ndarray, lbls: np.ndarray) -> list[np.ndarray]:
    """Cut the concatenated frames into trials by their one-hot membership (columns in order)."""
    member = lbls.argmax(axis=1)
    if np.any(np.diff(member) < 0):
        raise DatasetError("cmu35WalkJog.mat: trial labels are not contiguous")
    return [Y[member == k] for k in range(lbls.shape[1]) if np.any(member == k)]


def load_cmu35(folder: str | Path) -> Cmu35:
    """Read ``cmu35WalkJog.mat`` and ``cmu35TaylorScaleBias.mat`` from ``folder``."""
    import scipy.io  # heavy; only needed here

    folder = Path(folder)
    try:
        d = scipy.io.loadmat(folder / "cmu35WalkJog.mat")
        sb = scipy.io.loadmat(folder / "cmu35TaylorScaleBias.mat")
        Y, lbls, Yt, lt = d["Y"], d["lbls"], d["Ytest"], d["lblstest"]
        scale, bias = sb["scale"].ravel(), sb["bias"].ravel()
    except (OSError, KeyError, ValueError) as exc:
        raise DatasetError(f"{folder}: cannot read the CMU subject 35 data: {exc}") from exc
    if Y.shape[1] != 62 or Yt.shape[1] != 62 or scale.shape != (59,):
        raise DatasetError(f"{folder}: expected 62 channels and a 59-value scale/bias")
    train = _split(Y.astype(np.float64), lbls)
    if len(train) != len(TRAIN_TRIALS):
        raise DatasetError(f"{folder}: expected {len(TRAIN_TRIALS)} training trials, got {len(train)}")
    test_jog, test_walk = _split(Yt.astype(np.float64), lt)
    labels = {n: ("jog" if int(n[3:]) in JOG_TRIALS else "walk") for n in TRAIN_TRIALS}
    labels.update({"35_18": "jog", "35_29": "walk"})
    return Cmu35(train, list(TRAIN_TRIALS), {"35_18": test_jog, "35_29": test_walk},
                 scale.astype(np.float64), bias.astype(np.float64), labels=labels)


def taylor59(channels: np.ndarray) -> np.ndarray:
    """(T, 62) degrees -> (T, 59): root xyz, sin(rot 3), cos(rot 3), wrapped joint angles (deg)."""
    r = np.deg2rad(channels[:, 3:6])
    joints = np.rad2deg(np.arcsin(np.sin(np.deg2rad(channels[:, JOINT_CHANNELS]))))
    return np.hstack([channels[:, :3], np.sin(r), np.cos(r), joints])


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

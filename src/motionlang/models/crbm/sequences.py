"""Training sequences of an order-n model: validation, and the rows and past frames a
minibatch reads (shared by the CRBM and the autoregressive baseline)."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.errors import MotionFormatError


def check_sequences(sequences: Sequence[np.ndarray], dim: int | None, min_frames: int,
                    what: str = "sequence") -> list[np.ndarray]:
    """Validate a list of (T_i, D) arrays: 2-D, same D (= ``dim`` if given), finite,
    T_i >= ``min_frames`` (an order-n model needs n + 1 to learn from, n to start from).

    Raises :class:`MotionFormatError` naming the sequence and frame of the first problem.
    """
    out = []
    if len(sequences) == 0:
        raise MotionFormatError(None, f"no {what}s given")
    for i, s in enumerate(sequences):
        s = np.asarray(s, dtype=np.float64)
        name = f"<{what} {i}>"
        if s.ndim != 2:
            raise MotionFormatError(name, f"expected a (frames, dims) array, got shape {s.shape}")
        if dim is not None and s.shape[1] != dim:
            raise MotionFormatError(name, f"expected {dim} dimensions per frame, got {s.shape[1]}")
        if s.shape[0] < min_frames:
            raise MotionFormatError(name, f"{s.shape[0]} frames: at least {min_frames} needed "
                                    f"(the model's order of past frames, plus the frame itself)")
        bad = ~np.isfinite(s)
        if bad.any():
            f, d = np.argwhere(bad)[0]
            raise MotionFormatError(name, f"non-finite value in dimension {d}", frame=int(f))
        dim = s.shape[1]
        out.append(s)
    return out


def chunk_index(lengths: Sequence[int], order: int) -> np.ndarray:
    """Rows (into the concatenation of sequences of ``lengths``) that have ``order`` past
    frames inside the same sequence; a minibatch is a set of these, never a copied chunk."""
    starts = np.cumsum([0] + list(lengths[:-1]))
    return np.concatenate([np.arange(s + order, s + n) for s, n in zip(starts, lengths)])


def gather_past(frames: np.ndarray, rows: np.ndarray, order: int) -> np.ndarray:
    """(len(rows), order*D): ``[v_{t-1}, ..., v_{t-order}]`` for each row t of ``frames`` (N, D)."""
    return np.concatenate([frames[rows - k] for k in range(1, order + 1)], axis=1)


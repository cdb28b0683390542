"""Model frames: the per-frame vectors the seq2seq models read and write.

A model frame is a feature set's normalised dimensions only: a trailing binary "active" flag
(``AnglesFeatures``) is dropped, since the L2M predicts its own end-of-motion flag.
"""
from __future__ import annotations

from typing import Any

import numpy as np


def model_dim(fs: Any) -> int:
    """Frame size the models see: the feature set's dims without its active flag."""
    return int(getattr(fs, "n_normalised", fs.dim))


def motion_frames(fs: Any, motion, offsets: int = 1) -> list[np.ndarray]:
    """Up to ``offsets`` sequences (T, model_dim) float32 of one motion (start offsets
    of the down-sampling, for feature sets that have them)."""
    seqs = fs.encode_all(motion)[:max(1, offsets)] if hasattr(fs, "encode_all") \
        else [fs.encode(motion)]
    n = model_dim(fs)
    return [np.ascontiguousarray(s[:, :n], dtype=np.float32) for s in seqs]


def frames_to_features(fs: Any, frames: np.ndarray) -> np.ndarray:
    """Model frames (T, model_dim) -> the feature set's (T, dim), active flag set to 1."""
    extra = fs.dim - frames.shape[1]
    if extra <= 0:
        return frames
    return np.concatenate([frames, np.ones((len(frames), extra), frames.dtype)], axis=1)

"""Motion-generation metrics of Ghosh et al. (2021): APE, AVE, CEE and SEE.

All functions are pure numpy. Sequences come as one array (N, T, J, 3) or as a list of N
arrays (T_i, J, 3) (different lengths allowed; prediction and target of one item must have
the same length). Position metrics return values in the unit of the input; the wrapper
:func:`position_metrics_mm` takes metres and reports **millimetres**.

Definitions (paper, Section 5.1), for N test sequences of T frames, joint j::

    APE[j] = 1/(N T) sum_n sum_t || Y_t[j] - Y^_t[j] ||_2
    AVE[j] = 1/N     sum_n       || s[j] - s^[j] ||_2,   s[j] = 1/(T-1) sum_t (Y_t[j] - mean_t Y[j])^2

(``s[j]`` is the per-axis temporal variance, a 3-vector, unbiased). With lists of
different lengths, APE weights each sequence by its frame count (a mean over all frames).

The paper reports APE/AVE "for the root joint" (the global trajectory) and "mean over the
local joints". Here *local* = positions in the body's heading frame (origin on the ground
below the root, facing +Z; ``features.positions.split_global``) for the 20 non-root
joints, and *root* = the root joint's global position. Note: the authors' released code
evaluates on normalised features (unit-less z-scores); we undo the normalisation and
report millimetres, so our numbers are not comparable digit for digit with theirs.

CEE and SEE compare a pose embedding with a sentence embedding of the same item (the
joint-embedding quality): CEE is the root-mean-square difference of the embeddings, SEE
the root-mean-square difference of their Gram matrices ``G = z z^T`` (D, D), each
averaged over the N items — the definitions the authors' evaluation code implements.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.positions import split_global

Seqs = np.ndarray | Sequence[np.ndarray]


def _pairs(pred: Seqs, target: Seqs) -> list[tuple[np.ndarray, np.ndarray]]:
    """-> list of (pred (T, J, 3), target (T, J, 3)) float64 pairs, shapes checked."""
    if isinstance(pred, np.ndarray) and pred.ndim == 3:
        pred, target = [pred], [np.asarray(target)]
    if len(pred) != len(target):
        raise MotionlangError(f"{len(pred)} predicted sequences but {len(target)} targets")
    if len(pred) == 0:
        raise MotionlangError("no sequences to evaluate")
    out = []
    for i, (p, t) in enumerate(zip(pred, target)):
        p, t = np.asarray(p, dtype=np.float64), np.asarray(t, dtype=np.float64)
        if p.shape != t.shape or p.ndim != 3 or p.shape[-1] != 3 or len(p) == 0:
            raise MotionlangError(f"sequence {i}: prediction {p.shape} and target {t.shape} "
                                  "must both be (T, J, 3) with T >= 1")
        out.append((p, t))
    return out


def ape(pred: Seqs, target: Seqs) -> np.ndarray:
    """Average position error per joint.

    Args:
        pred, target: (N, T, J, 3) or lists of (T_i, J, 3), same shapes pairwise.

    Returns:
        (J,) mean over all frames of all sequences of the Euclidean distance, input units.
    """
    pairs = _pairs(pred, target)
    total = sum(np.linalg.norm(p - t, axis=-1).sum(axis=0) for p, t in pairs)
    return total / sum(len(p) for p, _ in pairs)


def temporal_variance(x: np.ndarray) -> np.ndarray:
    """x (T, J, 3) -> (J, 3) per-axis variance over time, unbiased (divides by T - 1)."""
    if len(x) < 2:
        raise MotionlangError("the variance over time needs at least 2 frames")
    return np.var(x, axis=0, ddof=1)


def ave(pred: Seqs, target: Seqs) -> np.ndarray:
    """Average variance error per joint.

    Returns:
        (J,) mean over sequences of ``|| var_t(target) - var_t(pred) ||_2`` (the variances
        are 3-vectors per joint), in squared input units (m^2 for metres).
    """
    pairs = _pairs(pred, target)
    return np.mean([np.linalg.norm(temporal_variance(t) - temporal_variance(p), axis=-1)
                    for p, t in pairs], axis=0)


def _as_2d(z, name: str) -> np.ndarray:
    z = np.asarray(z, dtype=np.float64)
    if z.ndim == 1:
        z = z[None]
    if z.ndim != 2:
        raise MotionlangError(f"{name} must be (N, D) embeddings, got {z.shape}")
    return z


def cee(z_pose, z_text) -> float:
    """Content encoding error: mean over items of the RMS difference of two embeddings.

    Args:
        z_pose, z_text: (N, D) (or (D,)) pose and sentence embeddings of the same N items.

    Returns:
        ``mean_n sqrt(mean_d (z_pose[n, d] - z_text[n, d])^2)``.
    """
    a, b = _as_2d(z_pose, "z_pose"), _as_2d(z_text, "z_text")
    if a.shape != b.shape:
        raise MotionlangError(f"embedding shapes differ: {a.shape} vs {b.shape}")
    return float(np.mean(np.sqrt(np.mean((a - b) ** 2, axis=1))))


def gram(z) -> np.ndarray:
    """(N, D) embeddings -> (N, D, D) Gram (outer-product) matrices ``z_n z_n^T``."""
    z = _as_2d(z, "z")
    return z[:, :, None] * z[:, None, :]


def see(z_pose, z_text) -> float:
    """Style encoding error: mean over items of the RMS difference of the Gram matrices.

    Returns:
        ``mean_n sqrt(mean_{i,k} (G_pose[n, i, k] - G_text[n, i, k])^2)``, G from :func:`gram`.
    """
    a, b = _as_2d(z_pose, "z_pose"), _as_2d(z_text, "z_text")
    if a.shape != b.shape:
        raise MotionlangError(f"embedding shapes differ: {a.shape} vs {b.shape}")
    return float(np.mean(np.sqrt(np.mean((gram(a) - gram(b)) ** 2, axis=(1, 2)))))


def position_metrics_mm(pred: Seqs, target: Seqs) -> dict[str, object]:
    """APE and AVE of 21-joint KIT sequences, in millimetres (AVE in mm^2).

    Args:
        pred, target: global joint positions (N, T, 21, 3) or lists of (T_i, 21, 3), metres,
            Y up, joints in ``features.joint_map.KIT21_NAMES`` order (``PositionFeatures
            .decode`` output, i.e. after undoing the normalisation).

    Returns:
        dict: ``ape_joints`` (21,) local-frame APE per joint (entry 0 = root height only),
        ``ape_local`` mean of the 20 non-root local joints, ``ape_root`` global root
        trajectory APE, and ``ave_joints`` / ``ave_local`` / ``ave_root`` likewise.
    """

    pairs = _pairs(pred, target)
    if pairs[0][0].shape[1] != 21:
        raise MotionlangError(f"expected 21 KIT joints, got {pairs[0][0].shape[1]}")
    # the heading frame is a function of the hips and shoulders, each sequence its own
    local_p = [split_global(p)[0] * 1000.0 for p, _ in pairs]
    local_t = [split_global(t)[0] * 1000.0 for _, t in pairs]
    root_p = [p[:, :1] * 1000.0 for p, _ in pairs]
    root_t = [t[:, :1] * 1000.0 for _, t in pairs]
    ape_j = ape(local_p, local_t)
    ave_j = ave(local_p, local_t)
    return {"ape_joints": ape_j, "ape_local": float(ape_j[1:].mean()),
            "ape_root": float(ape(root_p, root_t)[0]),
            "ave_joints": ave_j, "ave_local": float(ave_j[1:].mean()),
            "ave_root": float(ave(root_p, root_t)[0])}

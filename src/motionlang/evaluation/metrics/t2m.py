"""Text-to-motion metrics as the papers report them, as pure numpy functions of the
embeddings a pair of text and motion encoders gives.

Guo et al. 2022 (the ``text-to-motion`` evaluation, used on HumanML3D and KIT-ML by every
later paper): test pairs are taken in shuffled batches of 32, the last incomplete batch
dropped. In each batch every text ranks the 32 motions by Euclidean distance:

* R-precision top-k: the fraction of texts whose own motion is among the k nearest (k = 1, 2, 3);
* MM-Dist: the mean distance between a text and its own motion;
* FID: Frechet distance between Gaussians fitted to real and to generated motion embeddings;
* Diversity: mean distance of 300 random pairs of (generated) motion embeddings;
* MultiModality: mean distance of 10 random pairs among the 30 motions generated for each of
  100 texts.

Each is computed 20 times (new generations, new batches) and given as mean +- 1.96 std /
sqrt(20) (:func:`repeat`, :func:`mean_interval`).

TMR (Petrovich et al. 2023) retrieval: cosine similarity of the embeddings, every text
ranking every motion (text-to-motion) and the reverse; R@k is the percentage of queries
whose pair is among the first k, MedR the median rank (1 = first); ties share the mean of
their positions (:func:`retrieval_metrics`; from any similarity matrix and any set of pairs
that count as hits, :func:`retrieval_scores`).
"""
from __future__ import annotations

import logging
import warnings
from collections.abc import Callable

import numpy as np
from scipy import linalg

from motionlang.errors import MotionlangError

Rng = np.random.Generator | int | None
log = logging.getLogger(__name__)


def _rng(rng: Rng) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def _pairs(a, b, name: str = "embeddings") -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.ndim != 2 or a.shape != b.shape:
        raise MotionlangError(f"{name} must be two (N, D) arrays of one shape, got {a.shape} "
                              f"and {b.shape}")
    return a, b


def euclidean_distance_matrix(a, b) -> np.ndarray:
    """(N1, D), (N2, D) -> (N1, N2) with ``[i, j] = |a_i - b_j|``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != b.shape[1]:
        raise MotionlangError(f"need (N1, D) and (N2, D) arrays, got {a.shape} and {b.shape}")
    sq = (a ** 2).sum(1)[:, None] + (b ** 2).sum(1)[None, :] - 2.0 * a @ b.T
    return np.sqrt(np.maximum(sq, 0.0))   # rounding can make a zero distance slightly < 0


def top_k_hits(dist, top_k: int = 3) -> np.ndarray:
    """(B, B) distances, text i's own motion at column i -> (B, top_k) bool: whether it is
    among the first k + 1 motions (ties: the stable order of ``argsort``)."""
    d = np.asarray(dist, dtype=float)
    order = np.argsort(d, axis=1, kind="stable")[:, :top_k]
    return np.cumsum(order == np.arange(len(d))[:, None], axis=1) > 0


def _batches(n: int, batch_size: int) -> list[slice]:
    if n < batch_size:
        raise MotionlangError(f"need at least one full batch of {batch_size} pairs, got {n}")
    return [slice(s, s + batch_size) for s in range(0, n - batch_size + 1, batch_size)]


def r_precision(text, motion, top_k: int = 3, batch_size: int = 32, rng: Rng = None
                ) -> np.ndarray:
    """Text (N, D) and motion (N, D) embeddings of N pairs -> (top_k,) R-precision top-1..k.

    Pairs are taken in consecutive batches of ``batch_size`` (shuffled first with ``rng``
    unless it is None), the last incomplete batch dropped, as the published evaluation.
    """
    t, m = _pairs(text, motion)
    if rng is not None:
        order = _rng(rng).permutation(len(t))
        t, m = t[order], m[order]
    hits = [top_k_hits(euclidean_distance_matrix(t[s], m[s]), top_k).sum(0)
            for s in _batches(len(t), batch_size)]
    return np.sum(hits, axis=0) / (len(hits) * batch_size)


def mm_dist(text, motion, batch_size: int = 32) -> float:
    """Mean |text_i - motion_i| over the pairs of the full batches (N, D), (N, D)."""
    t, m = _pairs(text, motion)
    n = len(_batches(len(t), batch_size)) * batch_size
    return float(np.linalg.norm(t[:n] - m[:n], axis=1).mean())


def activation_statistics(x) -> tuple[np.ndarray, np.ndarray]:
    """(N, D) embeddings -> mean (D,) and covariance (D, D) (``np.cov``, N - 1 divisor)."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or len(x) < 2:
        raise MotionlangError(f"need (N >= 2, D) embeddings, got {x.shape}")
    return x.mean(axis=0), np.cov(x, rowvar=False)


#: the imaginary part of the square root's diagonal taken as rounding (pytorch-fid's atol)
IMAG_TOL = 1e-3


def _sqrtm(a: np.ndarray) -> np.ndarray:
    with warnings.catch_warnings():   # singular products are handled by the caller
        warnings.simplefilter("ignore", linalg.LinAlgWarning)
        return linalg.sqrtm(a)


def _numerical(covmean: np.ndarray) -> bool:
    """Finite, and any imaginary part on the diagonal within :data:`IMAG_TOL`."""
    return bool(np.isfinite(covmean).all()) and (
        not np.iscomplexobj(covmean)
        or np.allclose(np.diagonal(covmean).imag, 0, atol=IMAG_TOL))


def frechet_distance(mu1, sigma1, mu2, sigma2, eps: float = 1e-6) -> float:
    """|mu1 - mu2|^2 + tr(S1 + S2 - 2 (S1 S2)^(1/2)) between two Gaussians.

    ``scipy.linalg.sqrtm`` of ``S1 S2``; an imaginary part whose diagonal stays within
    :data:`IMAG_TOL` is rounding and dropped (as the public FID code does). Otherwise the
    product is singular, as covariances of fewer samples than dimensions are: ``eps`` times
    the covariances' mean variance is added to both diagonals (then 10x, 100x ... up to
    ``1e4 eps``) until the root is numerical, and a warning says which offset was used.

    Raises:
        MotionlangError: shapes that disagree, or no offset in that range helps.
    """
    mu1, mu2 = np.atleast_1d(mu1).astype(float), np.atleast_1d(mu2).astype(float)
    s1, s2 = np.atleast_2d(sigma1).astype(float), np.atleast_2d(sigma2).astype(float)
    if mu1.shape != mu2.shape or s1.shape != s2.shape or s1.shape != (len(mu1),) * 2:
        raise MotionlangError(f"means {mu1.shape}, {mu2.shape} and covariances {s1.shape}, "
                              f"{s2.shape} do not agree")
    covmean = _sqrtm(s1 @ s2)
    if not _numerical(covmean):
        # relative to the data's scale, so that embeddings in any unit get the same offset
        scale = float(np.mean(np.r_[np.diagonal(s1), np.diagonal(s2)])) or 1.0
        for factor in (1.0, 10.0, 100.0, 1e3, 1e4):
            offset = np.eye(len(s1)) * (eps * factor * scale)
            covmean = _sqrtm((s1 + offset) @ (s2 + offset))
            if _numerical(covmean):
                log.warning("FID: the covariance product is singular (too few samples for "
                            "%d dimensions?): %.3g (%.3g x the mean variance) added to the "
                            "diagonals", len(s1), eps * factor * scale, eps * factor)
                break
        else:
            bad = np.abs(np.asarray(covmean).imag).max() if np.iscomplexobj(covmean) else np.nan
            raise MotionlangError(f"FID: imaginary part {bad:.3g} in the covariance square "
                                  f"root, even with {eps * 1e4:.3g} x the mean variance added "
                                  "to the diagonals")
    covmean = covmean.real
    diff = mu1 - mu2
    return float(diff @ diff + np.trace(s1) + np.trace(s2) - 2.0 * np.trace(covmean))


def fid(real, generated) -> float:
    """FID between real (N, D) and generated (M, D) motion embeddings."""
    return frechet_distance(*activation_statistics(real), *activation_statistics(generated))


def diversity(x, times: int = 300, rng: Rng = None) -> float:
    """Mean distance of ``times`` pairs of rows of (N > times, D): two independent draws of
    ``times`` distinct indices each."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or len(x) <= times:
        raise MotionlangError(f"diversity needs (N > {times}, D) embeddings, got {x.shape}")
    g = _rng(rng)
    first, second = g.choice(len(x), times, replace=False), g.choice(len(x), times, replace=False)
    return float(np.linalg.norm(x[first] - x[second], axis=1).mean())


def multimodality(x, times: int = 10, rng: Rng = None) -> float:
    """(texts, S > times, D): S motions generated per text -> mean distance of ``times``
    pairs of them per text, the same sample indices for every text."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 3 or x.shape[1] <= times:
        raise MotionlangError(f"multimodality needs (texts, S > {times}, D), got {x.shape}")
    g = _rng(rng)
    first = g.choice(x.shape[1], times, replace=False)
    second = g.choice(x.shape[1], times, replace=False)
    return float(np.linalg.norm(x[:, first] - x[:, second], axis=2).mean())


def hit_ranks(sims, hits) -> np.ndarray:
    """(Q, C) similarities of Q queries to C candidates and (Q, C) bool ``hits`` (the
    candidates that count as the query's pair; every query needs one) -> (Q,) 0-based rank
    of the query's best hit among the candidates by decreasing similarity: the number of
    other candidates above it, plus half of those tied with it (ties share the mean of their
    positions). Hits tied with the best hit do not count against it."""
    s, h = np.asarray(sims, dtype=float), np.asarray(hits, dtype=bool)
    if s.ndim != 2 or h.shape != s.shape:
        raise MotionlangError(f"similarities and hits must be one (Q, C) shape, got "
                              f"{s.shape} and {h.shape}")
    if not h.any(axis=1).all():
        raise MotionlangError(f"query {int(np.argmin(h.any(axis=1)))} has no hit among the "
                              "candidates")
    gt = np.where(h, s, -np.inf).max(axis=1)[:, None]
    better = ((s > gt) & ~h).sum(axis=1)
    equal = ((s == gt) & ~h).sum(axis=1)
    return better + equal / 2.0


def retrieval_ranks(sims, text_selfsim=None, threshold: float | None = None) -> np.ndarray:
    """(N, N) similarities, query i's pair at column i -> (N,) 0-based rank of the pair
    among the query's candidates by decreasing similarity; ties: the mean of their
    positions. With ``text_selfsim`` (N, N) and ``threshold`` t (TMR's, on the (1 + cos) / 2
    scale), any candidate j whose text has cosine > 2 t - 1 with text i also counts as the
    pair; the best of them is ranked (:func:`hit_ranks`)."""
    s = np.asarray(sims, dtype=float)
    if s.ndim != 2 or s.shape[0] != s.shape[1]:
        raise MotionlangError(f"similarities must be (N, N), got {s.shape}")
    hits = np.eye(len(s), dtype=bool)
    if text_selfsim is not None and threshold is not None:
        hits |= np.asarray(text_selfsim, dtype=float) > 2.0 * threshold - 1.0
    return hit_ranks(s, hits)


def retrieval_scores(sims, hits=None, ks=(1, 2, 3, 5, 10)) -> dict[str, float]:
    """TMR's measures from a (Q, C) text-to-motion similarity matrix, both directions:
    ``{"t2m/R01": %, ..., "t2m/MedR": rank, "m2t/R01": %, ..., "m2t/MedR": rank}``.

    Text -> motion: each row is a query ranking the C motions; motion -> text: each column
    ranks the Q texts. ``hits`` (Q, C) bool: which text-motion pairs count as matched
    (default: the diagonal of a square matrix). R@k: the percentage of queries whose best
    hit ranks among the first k; MedR: the median rank (1 = first); ties as
    :func:`hit_ranks`.
    """
    s = np.asarray(sims, dtype=float)
    if hits is None:
        if s.ndim != 2 or s.shape[0] != s.shape[1]:
            raise MotionlangError(f"similarities without hits must be (N, N), got {s.shape}")
        hits = np.eye(len(s), dtype=bool)
    h = np.asarray(hits, dtype=bool)
    out = {}
    for name, ranks in (("t2m", hit_ranks(s, h)), ("m2t", hit_ranks(s.T, h.T))):
        for k in ks:
            out[f"{name}/R{k:02d}"] = 100.0 * float(np.mean(ranks < k))
        out[f"{name}/MedR"] = float(np.median(ranks) + 1.0)
    return out


def retrieval_metrics(text, motion, ks=(1, 2, 3, 5, 10), text_selfsim=None,
                      threshold: float | None = None, batch_size: int | None = None
                      ) -> dict[str, float]:
    """TMR's measures from text (N, D) and motion (N, D) embeddings of N pairs (cosine
    similarity): ``{"t2m/R01": %, ..., "t2m/MedR": rank, "m2t/...": ...}``
    (:func:`retrieval_scores`; ``text_selfsim`` and ``threshold`` as
    :func:`retrieval_ranks`).

    ``batch_size``: TMR's small-batch protocol (32, after Guo et al.): the mean of the
    measures over consecutive full batches instead of one ranking among all N.
    """
    t, m = _pairs(text, motion)
    if batch_size is not None:
        sub = [retrieval_metrics(t[s], m[s], ks, None if text_selfsim is None else
                                 np.asarray(text_selfsim)[s, s], threshold)
               for s in _batches(len(t), batch_size)]
        return {k: float(np.mean([r[k] for r in sub])) for k in sub[0]}
    t = t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    m = m / np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-12)
    hits = np.eye(len(t), dtype=bool)
    if text_selfsim is not None and threshold is not None:
        hits |= np.asarray(text_selfsim, dtype=float) > 2.0 * threshold - 1.0
    return retrieval_scores(t @ m.T, hits, ks)


def mean_interval(values) -> tuple[np.ndarray | float, np.ndarray | float]:
    """Repetitions (n, ...) -> (mean, 1.96 std / sqrt(n)): the 95 % interval the papers
    print as "mean +- interval" (population std, as their ``get_metric_statistics``)."""
    v = np.asarray(values, dtype=float)
    if not len(v):
        raise MotionlangError("no repetitions")
    mean, half = v.mean(axis=0), 1.96 * v.std(axis=0) / np.sqrt(len(v))
    return (float(mean), float(half)) if v.ndim == 1 else (mean, half)


def repeat(fn: Callable[[int], object], n: int = 20) -> object:
    """Call ``fn(i)`` for i = 0..n-1 (a float, an array or a dict of them each time) ->
    :func:`mean_interval` of the results (a dict: per key)."""
    results = [fn(i) for i in range(n)]
    if results and isinstance(results[0], dict):
        return {k: mean_interval([r[k] for r in results]) for k in results[0]}
    return mean_interval(results)

"""Decoding motions from a mixture-density decoder: the sampled beam, mean decoding and
ancestral sampling.

A motion decoder is driven through one callable

    step(state, prev_frames (N, D) float) -> (MixtureParams over N rows, new_state)

giving the distribution of the next frame (in the model's feature space, usually
normalised) and of its "active" flag. Active = 1 means the motion goes on after this frame;
a hypothesis ends with the first frame whose sampled (or thresholded) flag is 0.
The score of a hypothesis is its log likelihood: the sum over frames of
log p(frame) + log P(flag), both under the model.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from motionlang.models.seq2seq.decode.beam import select_state
from motionlang.models.seq2seq.mdn import (
    MixtureParams,
    active_log_prob,
    mixture_log_prob,
    mixture_mean,
    mode_frame,
    sample,
)

MotionStep = Callable[[Any, torch.Tensor], "tuple[MixtureParams, Any]"]


@dataclass(frozen=True)
class MotionHypothesis:
    """frames: (T, D) float32 in the decoder's feature space; score: total log likelihood."""

    frames: np.ndarray
    score: float


def _start(start: torch.Tensor | None, B: int, D: int | None) -> torch.Tensor:
    if start is None:
        if D is None:
            raise ValueError("give either start frames or dim")
        return torch.zeros(B, D)
    start = torch.as_tensor(start, dtype=torch.float32)
    return start.expand(B, start.shape[-1]).clone() if start.dim() == 1 else start


@torch.no_grad()
def sampled_beam(step: MotionStep, state: Any, *, batch_size: int, width: int,
                 max_frames: int, samples: int = 5, min_frames: int = 1,
                 length_norm: bool = False, start: torch.Tensor | None = None,
                 dim: int | None = None, generator: torch.Generator | None = None,
                 temperature: float = 1.0,
                 reorder: Callable[[Any, torch.Tensor], Any] = select_state
                 ) -> list[list[MotionHypothesis]]:
    """The sampled beam of Plappert et al. (2018) for ``batch_size`` inputs.

    Args:
        step: the decoder step (module docstring); ``state`` has ``batch_size`` rows.
        width: W hypotheses kept and returned per input.
        max_frames: length cap; hypotheses still active at the cap are closed there.
        samples: S candidate (frame, flag) pairs drawn per live hypothesis and step.
        min_frames: the flag is held at 1 (and scored so) before this many frames.
        length_norm: rank finished hypotheses by log likelihood per frame instead of the
            total (the paper's). With normalised features a well-fitted frame has a positive
            log density, so the total favours motions that run to the cap.
        start: first decoder input, (D,) or (batch_size, D); zeros of ``dim`` if None.
        generator: torch RNG for reproducible sampling.
        temperature: candidates drawn from the mixture sharpened by tau (``mdn.sample``);
            they are scored under the model's own distribution.

    Returns:
        for each input, up to W hypotheses sorted by decreasing log likelihood (per frame
        with ``length_norm``); ``score`` is always the total.

    Each step draws S candidates for each live hypothesis; candidates whose flag is 0
    finish, the W most likely of the others stay live. Densities can exceed 1, so unlike
    word beams there is no early stop: decoding runs until no hypothesis is live or the cap.
    """
    B, W, S = batch_size, width, samples
    prev = _start(start, B, dim)
    D = prev.shape[-1]
    # One live row per input at first; later up to W. ``owner`` maps rows to inputs.
    owner = torch.arange(B)
    frames = torch.empty(B, 0, D)
    scores = torch.zeros(B)
    finished: list[list[MotionHypothesis]] = [[] for _ in range(B)]

    def rank(h: MotionHypothesis) -> float:
        return -h.score / len(h.frames) if length_norm else -h.score

    for t in range(max_frames):
        params, state = step(state, prev)
        xf, af, cand = _candidates(params, scores, S, D, generator, temperature,
                                   close=t == max_frames - 1, hold=t < min_frames - 1)
        row = torch.arange(len(owner)).repeat_interleave(S)
        keep_rows = _settle(finished, owner[row], af, cand, W, rank,
                            lambda i, frames=frames, row=row, xf=xf: torch.cat(
                                [frames[int(row[i])], xf[i:i + 1]]))
        if not keep_rows:
            break
        keep = torch.tensor(keep_rows)
        parent = row[keep]
        frames = torch.cat([frames[parent], xf[keep].unsqueeze(1)], dim=1)
        scores, owner, prev = cand[keep], owner[parent], xf[keep]
        state = reorder(state, parent)
    return finished


def _candidates(params: MixtureParams, scores: torch.Tensor, S: int, D: int,
                generator: torch.Generator | None, temperature: float, *, close: bool,
                hold: bool) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """S sampled (frame, flag) candidates per live row (N rows of ``params``, running log
    likelihoods ``scores`` (N,)): frames (N*S, D), flags (N*S,) (all 0 when ``close``, all
    1 when ``hold``) and the candidates' total log likelihoods (N*S,), rows in order."""
    N = len(scores)
    x, a = sample(params, S, generator, temperature)          # (N, S, D), (N, S)
    rep = MixtureParams(*(p.repeat_interleave(S, 0) for p in
                          (params.logit_pi, params.mu, params.log_sigma,
                           params.active_logit)))
    xf, af = x.reshape(N * S, D), a.reshape(N * S)
    if close:
        af = torch.zeros_like(af)                               # close everything at the cap
    elif hold:
        af = torch.ones_like(af)
    ll = mixture_log_prob(rep, xf) + active_log_prob(rep, af)
    return xf, af, scores.repeat_interleave(S) + ll


def _settle(finished: list[list[MotionHypothesis]], owner: torch.Tensor, af: torch.Tensor,
            cand: torch.Tensor, W: int, rank, motion_of) -> list[int]:
    """Per input: its candidates (``owner`` (N*S,) names the input) whose flag ``af`` is 0
    join its finished pool, which keeps its W best; the indices of its W most likely other
    candidates are returned, to stay live. ``motion_of(i)``: candidate i's frames (t+1, D)."""
    keep_rows: list[int] = []
    for b in range(len(finished)):
        mine = (owner == b)
        for i in (mine & (af == 0)).nonzero().flatten().tolist():
            seq = motion_of(i).numpy().astype(np.float32)
            finished[b].append(MotionHypothesis(seq, float(cand[i])))
        finished[b] = sorted(finished[b], key=rank)[:W]
        going = (mine & (af == 1)).nonzero().flatten()
        if len(going):
            best = cand[going].topk(min(W, len(going))).indices
            keep_rows.extend(going[best].tolist())
    return keep_rows


@torch.no_grad()
def mean_decode(step: MotionStep, state: Any, *, batch_size: int, max_frames: int,
                start: torch.Tensor | None = None, dim: int | None = None,
                threshold: float = 0.5, min_frames: int = 1,
                generator: torch.Generator | None = None,
                sample_frames: bool = False, temperature: float = 1.0,
                expected: bool = False, first: torch.Tensor | None = None
                ) -> list[MotionHypothesis]:
    """Decoding one motion per row: each frame is the mean of the heaviest mixture component
    (with ``expected``, the mixture's mean sum_k pi_k mu_k; with ``sample_frames``, a draw
    from the mixture: ancestral sampling), and the motion
    ends at the first frame whose P(active) < ``threshold`` (or the cap), but not before
    ``min_frames``. Scores are the log likelihood of the chosen frames and flags (under the
    model's own distribution, whatever the sampling ``temperature``: see ``mdn.sample``).

    The flag is thresholded rather than sampled even when frames are sampled: a per-frame
    stop probability of a few percent, drawn at every frame, ends most motions early.

    ``first`` (D,) or (B, D): the first output frame is this one instead of the model's
    (it is scored all the same), and decoding continues from it: a motion primed with a
    given first pose.
    """
    B = batch_size
    prev = _start(start, B, dim)
    given = None if first is None else _start(first, B, None)
    out: list[list[torch.Tensor]] = [[] for _ in range(B)]
    score = torch.zeros(B)
    alive = torch.ones(B, dtype=torch.bool)
    for t in range(max_frames):
        params, state = step(state, prev)
        x = (given if t == 0 and given is not None
             else sample(params, 1, generator, temperature)[0][:, 0] if sample_frames
             else mixture_mean(params) if expected else mode_frame(params))
        a = (torch.sigmoid(params.active_logit) >= threshold).float()
        if t == max_frames - 1:
            a = torch.zeros_like(a)
        elif t < min_frames - 1:
            a = torch.ones_like(a)
        ll = mixture_log_prob(params, x) + active_log_prob(params, a)
        score = score + torch.where(alive, ll, torch.zeros(B))
        for b in alive.nonzero().flatten().tolist():
            out[b].append(x[b])
        alive = alive & (a == 1)
        if not bool(alive.any()):
            break
        prev = x
    return [MotionHypothesis(torch.stack(o).numpy().astype(np.float32), float(s))
            for o, s in zip(out, score)]


def sample_decode(step: MotionStep, state: Any, *, width: int, max_frames: int,
                  dim: int | None = None, start: torch.Tensor | None = None,
                  min_frames: int = 1, generator: torch.Generator | None = None,
                  length_norm: bool = False, temperature: float = 1.0,
                  reorder: Callable[[Any, torch.Tensor], Any] = select_state,
                  first: torch.Tensor | None = None) -> list[MotionHypothesis]:
    """W independent ancestral samples for ONE input (``state`` has one row), drawn at
    ``temperature`` (``mdn.sample``), sorted by decreasing log likelihood (per frame with
    ``length_norm``); ``first`` (D,): a given first frame (see :func:`mean_decode`)."""
    rows = reorder(state, torch.zeros(width, dtype=torch.long))
    hyps = mean_decode(step, rows, batch_size=width, max_frames=max_frames, start=start,
                       dim=dim, min_frames=min_frames, generator=generator,
                       sample_frames=True, temperature=temperature, first=first)
    return sorted(hyps, key=lambda h: -h.score / (len(h.frames) if length_norm else 1))

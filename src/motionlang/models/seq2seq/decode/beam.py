"""Beam search and greedy decoding over words, independent of any model.

A decoder is driven through one callable

    step(state, prev_tokens (N,) long) -> (log_probs (N, V) float, new_state)

where N = batch x beam rows and ``log_probs`` are normalised (log-softmax) next-word
log probabilities. ``state`` is anything :func:`select_state` can reorder: tensors whose
first dimension is N, or tuples / lists / dicts of them (other values are passed through).

Every returned hypothesis ends with EOS and is ranked by its total log probability
(sum over its tokens, EOS included); ``max_len`` caps the number of generated tokens,
EOS included, so a hypothesis that reaches the cap is closed with EOS.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import torch

Step = Callable[[Any, torch.Tensor], "tuple[torch.Tensor, Any]"]


@dataclass(frozen=True)
class Hypothesis:
    """A decoded sentence: token ids (SOS excluded, EOS last) and total log probability."""

    tokens: tuple[int, ...]
    score: float


def select_state(state: Any, index: torch.Tensor) -> Any:
    """Rows ``index`` of every tensor in ``state`` (dim 0), recursing into containers."""
    if isinstance(state, torch.Tensor):
        return state.index_select(0, index)
    if isinstance(state, tuple) and hasattr(state, "_fields"):  # namedtuple
        return type(state)(*(select_state(s, index) for s in state))
    if isinstance(state, (tuple, list)):
        return type(state)(select_state(s, index) for s in state)
    if isinstance(state, dict):
        return {k: select_state(v, index) for k, v in state.items()}
    return state


def _ban(log_probs: torch.Tensor, banned: Sequence[int]) -> torch.Tensor:
    if banned:
        log_probs = log_probs.clone()
        log_probs[:, list(banned)] = float("-inf")
    return log_probs


@torch.no_grad()
def beam_search(step: Step, state: Any, *, batch_size: int, width: int, sos: int, eos: int,
                max_len: int, banned: Sequence[int] = (), min_len: int = 0,
                reorder: Callable[[Any, torch.Tensor], Any] = select_state,
                length_penalty: float = 0.0, prefix: Sequence[int] = ()
                ) -> list[list[Hypothesis]]:
    """Beam search for ``batch_size`` independent inputs.

    Args:
        step: the decoder step (see module docstring).
        state: initial decoder state with ``batch_size`` rows; it is expanded to
            ``batch_size * width`` rows (row b * width + w is beam w of input b).
        width: beam width W; also the number of hypotheses returned per input.
        sos, eos: start and end token ids. ``banned``: ids never generated (PAD, SOS...).
        max_len: at most this many generated tokens per hypothesis, EOS included.
        min_len: at least this many tokens before EOS (1 rules out the empty sentence).
        length_penalty: alpha >= 0; finished hypotheses are ranked by total log probability
            / (number of tokens) ** alpha. 0 (default) ranks by the total, the paper's
            choice; the total favours short sentences (every word costs log probability),
            alpha = 1 ranks by the mean per token. With alpha > 0 the search runs to
            ``max_len`` (a longer hypothesis can still overtake).
        prefix: tokens every hypothesis starts with (fed to the decoder and scored, never
            searched); they count towards ``max_len`` and ``min_len``.

    Returns:
        for each input, up to W hypotheses sorted by decreasing rank score; ``score`` is
        always the total log probability.

    At every step each of the W live prefixes is extended by every word; the extensions
    by EOS join the input's finished pool (its W best are kept) and the W best other
    extensions stay live. Since log probabilities are <= 0 a prefix can only lose score,
    so an input stops as soon as its best live prefix scores no more than the worst of W
    finished hypotheses.
    """
    B, W = batch_size, width
    _check_beam_args(W, max_len, length_penalty)
    rank = _ranker(length_penalty)
    state = reorder(state, torch.arange(B).repeat_interleave(W))
    prev = torch.full((B * W,), sos, dtype=torch.long)
    # Only beam 0 is live at the start so the W copies of the empty prefix don't repeat.
    scores = torch.full((B, W), float("-inf"))
    scores[:, 0] = 0.0
    tokens = torch.empty(B, W, 0, dtype=torch.long)
    for tok_id in prefix:
        log_probs, state = step(state, prev)
        scores = scores + log_probs.float()[:, tok_id].view(B, W)
        prev = torch.full((B * W,), tok_id, dtype=torch.long)
        tokens = torch.cat([tokens, prev.view(B, W, 1)], dim=-1)
    finished: list[list[Hypothesis]] = [[] for _ in range(B)]
    done = torch.zeros(B, dtype=torch.bool)
    for t in range(len(prefix), max_len):
        log_probs, state = step(state, prev)
        V = log_probs.shape[-1]
        ban = tuple(banned) + ((eos,) if t < min_len and t < max_len - 1 else ())
        total = scores.unsqueeze(-1) + _ban(log_probs.float(), ban).view(B, W, V)
        _finish(finished, total[..., eos], tokens, done, eos, rank, W)
        if t == max_len - 1:
            break
        total[..., eos] = float("-inf")
        scores, beam, tok, tokens = _extend(total, tokens, W)
        if not length_penalty:  # with a penalty a longer hypothesis can still overtake
            _mark_settled(done, scores, finished, W)
        scores[done] = float("-inf")
        if bool(done.all()) or not bool(torch.isfinite(scores).any()):
            break
        state = reorder(state, (beam + torch.arange(B).unsqueeze(1) * W).view(-1))
        prev = tok.view(-1)
    return finished


def _extend(total: torch.Tensor, tokens: torch.Tensor, W: int):
    """The W best extensions per input of the prefixes ``tokens`` (B, W, t) by the totals
    ``total`` (B, W, V): their scores (B, W), source beams, new tokens and prefixes
    (B, W, t + 1)."""
    B, _, V = total.shape
    scores, flat = total.view(B, W * V).topk(W, dim=1)
    beam, tok = flat // V, flat % V
    tokens = torch.cat([tokens.gather(1, beam.unsqueeze(-1).expand(B, W, tokens.shape[-1])),
                        tok.unsqueeze(-1)], dim=-1)
    return scores, beam, tok, tokens


def _check_beam_args(W: int, max_len: int, length_penalty: float) -> None:
    """ValueError unless the width and cap are >= 1 and the length penalty >= 0."""
    if W < 1 or max_len < 1:
        raise ValueError("beam width and max_len must be >= 1")
    if length_penalty < 0:
        raise ValueError("length_penalty must be >= 0")


def _ranker(length_penalty: float) -> Callable[[Hypothesis], float]:
    """Sort key of finished hypotheses: minus total log probability / tokens ** alpha."""
    def rank(h: Hypothesis) -> float:
        return -h.score / (len(h.tokens) ** length_penalty if length_penalty else 1.0)
    return rank


def _finish(finished: list[list[Hypothesis]], eos_total: torch.Tensor, tokens: torch.Tensor,
            done: torch.Tensor, eos: int, rank, W: int) -> None:
    """Add each live prefix closed by EOS (total (B, W), prefixes (B, W, t)) to its input's
    pool, inputs already done excepted, and keep each pool's W best."""
    for b, w in (torch.isfinite(eos_total) & ~done.unsqueeze(1)).nonzero().tolist():
        finished[b].append(Hypothesis(tuple(tokens[b, w].tolist()) + (eos,),
                                      float(eos_total[b, w])))
    for b in range(len(finished)):
        finished[b] = sorted(finished[b], key=rank)[:W]


def _mark_settled(done: torch.Tensor, scores: torch.Tensor,
                  finished: list[list[Hypothesis]], W: int) -> None:
    """Mark done each input whose W finished hypotheses all beat its best live prefix
    (scores (B, W), best first): log probabilities <= 0, so no prefix can catch up."""
    for b in range(len(finished)):
        if len(finished[b]) >= W and not scores[b, 0] > finished[b][-1].score:
            done[b] = True


@torch.no_grad()
def greedy_search(step: Step, state: Any, *, batch_size: int, sos: int, eos: int,
                  max_len: int, banned: Sequence[int] = (), min_len: int = 0
                  ) -> list[Hypothesis]:
    """Take the most probable word at every step; one hypothesis per input.

    At the last allowed step EOS is forced (its log probability is still counted); before
    ``min_len`` tokens EOS is not allowed.
    """
    B = batch_size
    prev = torch.full((B,), sos, dtype=torch.long)
    score = torch.zeros(B)
    out: list[list[int]] = [[] for _ in range(B)]
    alive = torch.ones(B, dtype=torch.bool)
    for t in range(max_len):
        log_probs, state = step(state, prev)
        ban = tuple(banned) + ((eos,) if t < min_len and t < max_len - 1 else ())
        log_probs = _ban(log_probs.float(), ban)
        tok = log_probs.argmax(-1)
        if t == max_len - 1:
            tok = torch.full_like(tok, eos)
        score = score + torch.where(alive, log_probs.gather(1, tok.unsqueeze(1)).squeeze(1),
                                    torch.zeros(B))
        for b in alive.nonzero().flatten().tolist():
            out[b].append(int(tok[b]))
        alive = alive & (tok != eos)
        if not bool(alive.any()):
            break
        prev = tok
    return [Hypothesis(tuple(o), float(s)) for o, s in zip(out, score)]

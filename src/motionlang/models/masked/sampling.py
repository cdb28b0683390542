"""Masking in training and iterative decoding in sampling (MaskGIT, Chang et al. 2022, as
MoMask uses it for motion tokens).

Training masks a fraction ``cos(pi/2 * tau)`` of each motion's tokens, tau uniform in [0, 1]
(:func:`mask_ratio`): from all of them to one. Of the masked tokens 80 % show the mask
token, 10 % a random code and 10 % their own (BERT's corruption, so that the model also
checks the tokens it sees). Decoding starts with every free token masked; each of ``steps``
iterations predicts the masked ones, keeps the most confident and masks the rest again, so
that after iteration s a fraction ``cos(pi/2 * s / steps)`` is still masked. Kept tokens
(in-betweening) are never masked.
"""
from __future__ import annotations

import math
from collections.abc import Callable

import torch


def mask_ratio(t: torch.Tensor | float) -> torch.Tensor:
    """The cosine schedule: the masked fraction at time t in [0, 1] (1 -> 0)."""
    return torch.cos(torch.as_tensor(t, dtype=torch.float32) * (math.pi / 2))


def training_mask(valid: torch.Tensor) -> torch.Tensor:
    """Valid positions (B, L) -> the positions to mask (B, L): a schedule fraction of each
    row's valid positions, at least one, chosen uniformly (torch's global generator)."""
    B, L = valid.shape
    n_valid = valid.sum(1)
    ratio = mask_ratio(torch.rand(B, device=valid.device))
    n_mask = (ratio * n_valid).ceil().clamp(min=1).long()
    score = torch.rand(B, L, device=valid.device).masked_fill(~valid, 2.0)
    rank = score.argsort(1).argsort(1)
    return (rank < n_mask[:, None]) & valid


def corrupt(tokens: torch.Tensor, masked: torch.Tensor, codes: int, mask_id: int
            ) -> torch.Tensor:
    """The input the transformer sees: masked positions get the mask token (80 %), a random
    code (10 %) or stay (10 %)."""
    u = torch.rand(tokens.shape, device=tokens.device)
    out = tokens.clone()
    out[masked & (u < 0.8)] = mask_id
    random = masked & (u >= 0.8) & (u < 0.9)
    out[random] = torch.randint(0, codes, (int(random.sum()),), device=tokens.device)
    return out


def guided(logits_fn: Callable[[torch.Tensor, torch.Tensor | None], torch.Tensor],
           tokens: torch.Tensor, scale: float) -> torch.Tensor:
    """Classifier-free guidance: ``uncond + scale * (cond - uncond)`` of the logits;
    ``logits_fn(tokens, drop)`` runs the model on a batch with the condition dropped where
    ``drop`` is True (None: kept). Both halves go through the model as one batch of 2B
    rows (one pass, not two); scale 1 is the conditioned model alone."""
    if scale == 1.0:
        return logits_fn(tokens, None)
    B = tokens.shape[0]
    drop = torch.arange(2 * B, device=tokens.device) >= B
    both = logits_fn(torch.cat([tokens, tokens]), drop)
    cond, uncond = both[:B], both[B:]
    return uncond + scale * (cond - uncond)


def pick(logits: torch.Tensor, temperature: float, top_k: int,
         generator: torch.Generator) -> tuple[torch.Tensor, torch.Tensor]:
    """Logits (..., K) -> (chosen codes (...), their probabilities (...)): drawn at
    ``temperature`` among the ``top_k`` likeliest (0: all), or the likeliest at
    temperature 0."""
    logits = logits.float().cpu()
    if top_k and top_k < logits.shape[-1]:
        kth = logits.topk(top_k, dim=-1).values[..., -1:]
        logits = logits.masked_fill(logits < kth, float("-inf"))
    if temperature == 0:
        probs = logits.softmax(-1)
        chosen = probs.argmax(-1)
    else:
        probs = (logits / temperature).softmax(-1)
        chosen = torch.multinomial(probs.reshape(-1, probs.shape[-1]), 1,
                                   generator=generator).reshape(probs.shape[:-1])
    return chosen, probs.gather(-1, chosen[..., None])[..., 0]


def decode_base(predict: Callable[[torch.Tensor, torch.Tensor | None], torch.Tensor],
                valid: torch.Tensor, mask_id: int, *, steps: int, guidance: float,
                temperature: float, top_k: int, generator: torch.Generator,
                known: torch.Tensor | None = None, kept: torch.Tensor | None = None
                ) -> torch.Tensor:
    """Iterative masked decoding of base tokens (B, L) (see module docstring).

    Args:
        predict: ``(tokens (B', L), drop (B',) or None) -> logits (B', L, K)``; B' is B,
            or 2B under guidance (the rows twice: conditioned, then not).
        valid: (B, L) positions inside each motion.
        known, kept: tokens (B, L) and where they are given (in-betweening); None: none.
    """
    device = valid.device
    kept = torch.zeros_like(valid) if kept is None else kept & valid
    tokens = torch.full(valid.shape, mask_id, dtype=torch.long, device=device)
    if known is not None:
        tokens = torch.where(kept, known.to(device), tokens)
    free = valid & ~kept
    n_free = free.sum(1)
    for s in range(steps):
        masked = free & (tokens == mask_id)
        if not masked.any():
            break
        logits = guided(predict, tokens, guidance)
        chosen, conf = pick(logits, temperature, top_k, generator)
        chosen, conf = chosen.to(device), conf.to(device)
        tokens = torch.where(masked, chosen, tokens)
        # the newly chosen compete for staying; decided and given tokens stay
        conf = torch.where(masked, conf, torch.full_like(conf, math.inf))
        n_left = (mask_ratio((s + 1) / steps) * n_free).floor().long()
        rank = conf.argsort(1).argsort(1)
        tokens = torch.where((rank < n_left[:, None]) & masked, mask_id, tokens)
    return torch.where(valid, tokens, 0)   # padding as in training: code 0, never read


def decode_residual(predict: Callable[[torch.Tensor, int, torch.Tensor | None], torch.Tensor],
                    base: torch.Tensor, n_q: int, *, guidance: float,
                    known: torch.Tensor | None = None, kept: torch.Tensor | None = None
                    ) -> torch.Tensor:
    """Base tokens (B, L) -> tokens of every codebook (B, L, n_q), each finer codebook the
    likeliest under guidance given the coarser ones; ``known`` (B, L, n_q) and ``kept``
    (B, L) as in :func:`decode_base`."""
    tokens = base[..., None]
    for j in range(1, n_q):
        def level(t: torch.Tensor, drop: torch.Tensor | None, j: int = j) -> torch.Tensor:
            return predict(t, j, drop)
        logits = guided(level, tokens, guidance)
        nxt = logits.argmax(-1)
        if known is not None and kept is not None:
            nxt = torch.where(kept, known[..., j].to(nxt.device), nxt)
        tokens = torch.cat([tokens, nxt[..., None]], -1)
    return tokens

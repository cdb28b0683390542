"""The motion tokenizer: a 1-D convolutional VQ-VAE with a residual quantiser.

* Encoder: frames (B, T, F) -> latents (B, T / 4, code_dim): two stride-2 convolutions, each
  followed by dilated residual blocks (dilations 1, 3, 9: each latent sees about a second).
* Residual quantiser (:class:`ResidualQuantizer`): codebook q quantises what codebooks
  0..q-1 left of the latent; the sum of the chosen codes is the quantised latent. The
  codebooks are not learnt by gradient but as exponential moving averages of the vectors
  assigned to each code (van den Oord et al. 2017, appendix), and a code that has gone
  unused is moved onto a vector of the batch (dead-code reset, as T2M-GPT), so that every
  code keeps working. In training, a batch quantises with the first k codebooks only with
  probability ``quantizer_dropout`` (k uniform in 1..Q), so that the base codes alone decode
  to a whole motion (MoMask's quantisation dropout).
* Decoder: the mirror of the encoder, nearest-neighbour upsampling by 2 twice.

T must be a multiple of 4 (:func:`pad_frames` repeats the last frame).
"""
from __future__ import annotations

from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from motionlang.models.masked.config import DOWN, MaskedConfig

#: a code whose moving-average count falls below this is reset (counts are in vectors per
#: batch, so this is "used less than once in a typical batch")
DEAD = 1.0


def pad_frames(x: torch.Tensor) -> torch.Tensor:
    """(B, T, F) -> (B, ceil(T / 4) * 4, F), the last frame repeated."""
    extra = (-x.shape[1]) % DOWN
    return x if not extra else torch.cat([x, x[:, -1:].expand(-1, extra, -1)], dim=1)


class ResBlock(nn.Module):
    """ReLU -> dilated conv -> ReLU -> 1x1 conv, added to its input (channels kept)."""

    def __init__(self, width: int, dilation: int):
        super().__init__()
        self.conv = nn.Conv1d(width, width, 3, padding=dilation, dilation=dilation)
        self.mix = nn.Conv1d(width, width, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.mix(F.relu(self.conv(F.relu(x))))


def _blocks(width: int, depth: int) -> list[nn.Module]:
    return [ResBlock(width, 3 ** (i % 3)) for i in range(depth)]


class Encoder(nn.Module):
    def __init__(self, c: MaskedConfig):
        super().__init__()
        layers: list[nn.Module] = [nn.Conv1d(c.n_features, c.width, 3, padding=1), nn.ReLU()]
        for _ in range(2):
            layers += [nn.Conv1d(c.width, c.width, 4, stride=2, padding=1),
                       *_blocks(c.width, c.depth)]
        layers.append(nn.Conv1d(c.width, c.code_dim, 3, padding=1))
        self.net = nn.Sequential(*layers)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x.transpose(1, 2)).transpose(1, 2)


class Decoder(nn.Module):
    def __init__(self, c: MaskedConfig):
        super().__init__()
        layers: list[nn.Module] = [nn.Conv1d(c.code_dim, c.width, 3, padding=1), nn.ReLU()]
        for _ in range(2):
            layers += [*_blocks(c.width, c.depth), nn.Upsample(scale_factor=2, mode="nearest"),
                       nn.Conv1d(c.width, c.width, 3, padding=1)]
        layers += [nn.ReLU(), nn.Conv1d(c.width, c.n_features, 3, padding=1)]
        self.net = nn.Sequential(*layers)

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.net(z.transpose(1, 2)).transpose(1, 2)


class ResidualQuantizer(nn.Module):
    """Q codebooks of K codes of size D, EMA-updated (see module docstring).

    Buffers: ``codebooks`` (Q, K, D), ``counts`` (Q, K) and ``sums`` (Q, K, D) (the moving
    averages), ``ready`` (set once the codebooks were seeded from the first batch).
    """

    codebooks: torch.Tensor
    counts: torch.Tensor
    sums: torch.Tensor
    ready: torch.Tensor

    def __init__(self, quantizers: int, codes: int, dim: int, decay: float, dropout: float):
        super().__init__()
        self.decay, self.dropout = decay, dropout
        self.register_buffer("codebooks", torch.zeros(quantizers, codes, dim))
        self.register_buffer("counts", torch.ones(quantizers, codes))
        self.register_buffer("sums", torch.zeros(quantizers, codes, dim))
        self.register_buffer("ready", torch.zeros((), dtype=torch.bool))

    @property
    def n_q(self) -> int:
        return int(self.codebooks.shape[0])

    def nearest(self, q: int, r: torch.Tensor) -> torch.Tensor:
        """Rows (N, D) -> index (N,) of the nearest code of codebook ``q``."""
        book = self.codebooks[q]
        d = (r * r).sum(1, keepdim=True) - 2 * r @ book.T + (book * book).sum(1)[None]
        return d.argmin(1)

    def lookup(self, indices: torch.Tensor) -> torch.Tensor:
        """Indices (..., k) of the first k codebooks -> the summed codes (..., D)."""
        return sum((self.codebooks[q][indices[..., q]] for q in range(indices.shape[-1])),
                   torch.zeros(*indices.shape[:-1], self.codebooks.shape[-1],
                               device=indices.device))

    @torch.no_grad()
    def _seed(self, rows: torch.Tensor) -> None:
        """Every codebook starts on vectors of the first batch (scaled down for the finer
        codebooks, whose residuals are smaller)."""
        for q in range(self.n_q):
            pick = torch.randint(0, len(rows), (self.codebooks.shape[1],), device=rows.device)
            self.codebooks[q] = rows[pick] * (0.5 ** q)
            self.sums[q] = self.codebooks[q].clone()
        self.ready.fill_(True)

    @torch.no_grad()
    def _update(self, q: int, r: torch.Tensor, idx: torch.Tensor) -> None:
        onehot = F.one_hot(idx, self.codebooks.shape[1]).to(r.dtype)      # (N, K)
        self.counts[q].mul_(self.decay).add_(onehot.sum(0), alpha=1 - self.decay)
        self.sums[q].mul_(self.decay).add_(onehot.T @ r, alpha=1 - self.decay)
        dead = self.counts[q] < DEAD
        if dead.any():   # move unused codes onto vectors of this batch
            pick = torch.randint(0, len(r), (int(dead.sum()),), device=r.device)
            self.sums[q][dead] = r[pick]
            self.counts[q][dead] = 1.0
        self.codebooks[q] = self.sums[q] / self.counts[q][:, None]

    def forward(self, z: torch.Tensor, mask: torch.Tensor, n_q: int | None = None,
                learn: bool | None = None) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Latents (B, L, D) and their mask (B, L) -> (quantised latents with straight-through
        gradients (B, L, D), indices (B, L, k), commitment loss); ``n_q``: use the first
        k codebooks (None: all, or fewer under quantiser dropout in training); ``learn``:
        update the codebooks (None: in training)."""
        learn = self.training if learn is None else learn
        rows = z[mask]
        if learn and not bool(self.ready) and len(rows):
            self._seed(rows.detach())
        k = self.n_q if n_q is None else n_q
        if n_q is None and self.training and float(torch.rand(())) < self.dropout:
            k = int(torch.randint(1, self.n_q + 1, ()))
        residual = z.detach()
        quantised = torch.zeros_like(z)
        indices, commit = [], z.new_zeros(())
        for q in range(k):
            flat = residual.reshape(-1, residual.shape[-1])
            idx = self.nearest(q, flat).reshape(residual.shape[:-1])
            if learn and len(rows):
                self._update(q, residual[mask], idx[mask])
            code = self.codebooks[q][idx]
            if mask.any():
                # what is left of the latent for this codebook, pulled towards its code
                commit = commit + F.mse_loss((z - quantised)[mask], code[mask])
            quantised = quantised + code
            residual = residual - code
            indices.append(idx)
        return z + (quantised - z).detach(), torch.stack(indices, -1), commit


class Tokenizer(nn.Module):
    """Encoder, residual quantiser and decoder (see module docstring)."""

    def __init__(self, c: MaskedConfig):
        super().__init__()
        self.encoder, self.decoder = Encoder(c), Decoder(c)
        self.quantizer = ResidualQuantizer(c.quantizers, c.codes, c.code_dim, c.ema,
                                           c.quantizer_dropout)

    def forward(self, x: torch.Tensor, mask: torch.Tensor, frozen: bool = False
                ) -> dict[str, Any]:
        """Frames (B, T, F) (T a multiple of 4), token mask (B, T / 4) -> ``{"recon" (B, T,
        F), "indices" (B, T / 4, k), "commit"}``. ``frozen``: the encoder and codebooks as
        they are (no gradient, no codebook update), only the decoder learns: the tokens
        stay those a trained generator was trained on."""
        if frozen:
            with torch.no_grad():
                quantised, indices, commit = self.quantizer(self.encoder(x), mask, learn=False)
            return {"recon": self.decoder(quantised), "indices": indices, "commit": commit}
        z = self.encoder(x)
        quantised, indices, commit = self.quantizer(z, mask)
        return {"recon": self.decoder(quantised), "indices": indices, "commit": commit}

    @torch.no_grad()
    def encode(self, x: torch.Tensor) -> torch.Tensor:
        """Frames (B, T, F) -> tokens (B, ceil(T / 4), Q) of every codebook."""
        x = pad_frames(x)
        z = self.encoder(x)
        mask = torch.ones(z.shape[:2], dtype=torch.bool, device=z.device)
        return self.quantizer(z, mask, self.quantizer.n_q)[1]

    @torch.no_grad()
    def decode(self, tokens: torch.Tensor) -> torch.Tensor:
        """Tokens (B, L, k) of the first k codebooks -> frames (B, 4 L, F)."""
        return self.decoder(self.quantizer.lookup(tokens))

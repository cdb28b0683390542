"""Mixture density output: K diagonal Gaussians over a frame plus a Bernoulli "active" flag.

Used by the language-to-motion decoder (Plappert, Mandery & Asfour 2018, after Graves 2013)
and by the sampled motion beam. All log densities are natural logs; a frame's density is the
product over its D dimensions, so log densities are summed over D.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F

LOG_2PI = math.log(2.0 * math.pi)


@dataclass
class MixtureParams:
    """Parameters of N mixtures (N = batch, or batch x time flattened).

    Attributes:
        logit_pi: (N, K) unnormalised log mixture weights.
        mu: (N, K, D) component means.
        log_sigma: (N, K, D) log standard deviations.
        active_logit: (N,) logit of P(active = 1), i.e. "the motion goes on after this frame".
    """

    logit_pi: torch.Tensor
    mu: torch.Tensor
    log_sigma: torch.Tensor
    active_logit: torch.Tensor

    def index(self, idx: torch.Tensor) -> MixtureParams:
        """Select rows ``idx`` (a LongTensor or boolean mask over N)."""
        return MixtureParams(self.logit_pi[idx], self.mu[idx], self.log_sigma[idx],
                             self.active_logit[idx])

    def flatten(self) -> MixtureParams:
        """(B, T, ...) -> (B*T, ...)."""
        K, D = self.mu.shape[-2:]
        return MixtureParams(self.logit_pi.reshape(-1, K), self.mu.reshape(-1, K, D),
                             self.log_sigma.reshape(-1, K, D), self.active_logit.reshape(-1))


class MixtureDensityHead(nn.Module):
    """Linear map from hidden features (..., H) to :class:`MixtureParams` over D dims.

    ``min_log_sigma`` floors the standard deviations: without it the likelihood of a
    (nearly) constant dimension grows without bound and training diverges.
    """

    def __init__(self, in_dim: int, dim: int, n_components: int, min_log_sigma: float = -7.0):
        super().__init__()
        self.dim, self.k, self.min_log_sigma = dim, n_components, min_log_sigma
        self.proj = nn.Linear(in_dim, n_components * (1 + 2 * dim) + 1)

    def forward(self, h: torch.Tensor) -> MixtureParams:
        """h: (..., H) -> params with leading shape (...)."""
        K, D = self.k, self.dim
        out = self.proj(h)
        lead = out.shape[:-1]
        logit_pi = out[..., :K]
        mu = out[..., K:K + K * D].reshape(*lead, K, D)
        log_sigma = out[..., K + K * D:K + 2 * K * D].reshape(*lead, K, D)
        log_sigma = log_sigma.clamp(min=self.min_log_sigma)
        return MixtureParams(logit_pi, mu, log_sigma, out[..., -1])


def component_log_density(params: MixtureParams, x: torch.Tensor,
                          weights: torch.Tensor | None = None) -> torch.Tensor:
    """log N(x | mu_k, diag sigma_k^2) for every component: x (N, D) -> (N, K).

    ``weights`` (D,), optional: each dimension's log density is multiplied by its weight
    (a training device that makes some dimensions count more; 1 everywhere = the density).
    """
    z = (x.unsqueeze(-2) - params.mu) * torch.exp(-params.log_sigma)
    per_dim = -0.5 * (z * z + LOG_2PI) - params.log_sigma
    return (per_dim if weights is None else per_dim * weights).sum(-1)


def mixture_log_prob(params: MixtureParams, x: torch.Tensor,
                     weights: torch.Tensor | None = None) -> torch.Tensor:
    """Exact log p(x) of the mixture (logsumexp over components): x (N, D) -> (N,);
    ``weights`` as in :func:`component_log_density`."""
    log_pi = F.log_softmax(params.logit_pi, dim=-1)
    return torch.logsumexp(log_pi + component_log_density(params, x, weights), dim=-1)


def surrogate_log_prob(params: MixtureParams, x: torch.Tensor,
                       weights: torch.Tensor | None = None) -> torch.Tensor:
    """The paper's stable surrogate: sum_k pi_k log N(x | k), x (N, D) -> (N,);
    ``weights`` as in :func:`component_log_density`.

    By Jensen's inequality it is a lower bound of :func:`mixture_log_prob`; it never takes
    the log of a sum of tiny densities, which is what makes it stable early in training.
    """
    pi = F.softmax(params.logit_pi, dim=-1)
    return (pi * component_log_density(params, x, weights)).sum(-1)


def active_log_prob(params: MixtureParams, active: torch.Tensor) -> torch.Tensor:
    """log P(active flag = a) for a in {0, 1}: (N,) -> (N,)."""
    return -F.binary_cross_entropy_with_logits(params.active_logit, active.float(),
                                               reduction="none")


def sample(params: MixtureParams, n: int, generator: torch.Generator | None = None,
           temperature: float = 1.0) -> tuple[torch.Tensor, torch.Tensor]:
    """Draw n frames and active flags per mixture: -> x (N, n, D), active (N, n) in {0, 1}.

    ``temperature`` tau < 1 samples a sharpened mixture: weights softmax(logits / tau) and
    standard deviations sigma * tau (in the spirit of the sampling "bias" of Graves 2013,
    arXiv:1308.0850, Sec. 5.4, which shrinks sigma by exp(-b) and scales the logits by 1 + b).
    tau = 1 is the model's own distribution; as tau -> 0 the draw tends to the heaviest
    component's mean (:func:`mode_frame`). The flags are not tempered.
    """
    if not temperature > 0:
        raise ValueError(f"temperature must be > 0, got {temperature}")
    N, K, D = params.mu.shape
    probs = F.softmax(params.logit_pi / temperature, dim=-1)
    comp = torch.multinomial(probs, n, replacement=True, generator=generator)  # (N, n)
    idx = comp.unsqueeze(-1).expand(N, n, D)
    mu = params.mu.gather(1, idx)
    sigma = params.log_sigma.gather(1, idx).exp() * temperature
    eps = torch.randn(N, n, D, generator=generator, dtype=mu.dtype)
    p_active = torch.sigmoid(params.active_logit).unsqueeze(-1).expand(N, n)
    active = torch.bernoulli(p_active, generator=generator)
    return mu + sigma * eps, active


def mixture_mean(params: MixtureParams) -> torch.Tensor:
    """Expected frame sum_k pi_k mu_k of each mixture: (N, K, D) params -> (N, D)."""
    return (F.softmax(params.logit_pi, dim=-1).unsqueeze(-1) * params.mu).sum(1)


def mode_frame(params: MixtureParams) -> torch.Tensor:
    """Mean of the heaviest component, a cheap stand-in for the mode: -> (N, D)."""
    k = params.logit_pi.argmax(-1)
    return params.mu[torch.arange(len(k)), k]

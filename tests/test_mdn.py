"""Mixture density maths against torch.distributions and scipy."""
from __future__ import annotations

import numpy as np
import pytest
import torch
from scipy.stats import multivariate_normal
from torch import distributions as td

from motionlang.models.seq2seq import mdn

torch.set_num_threads(1)


def random_params(N=6, K=4, D=3, seed=0) -> mdn.MixtureParams:
    g = torch.Generator().manual_seed(seed)
    return mdn.MixtureParams(torch.randn(N, K, generator=g), torch.randn(N, K, D, generator=g),
                             0.5 * torch.randn(N, K, D, generator=g), torch.randn(N, generator=g))


@pytest.mark.parametrize("seed", range(3))
def test_log_prob_matches_torch_distributions(seed):
    p = random_params(seed=seed)
    x = torch.randn(6, 3, generator=torch.Generator().manual_seed(100 + seed))
    ref = td.MixtureSameFamily(td.Categorical(logits=p.logit_pi),
                               td.Independent(td.Normal(p.mu, p.log_sigma.exp()), 1))
    torch.testing.assert_close(mdn.mixture_log_prob(p, x), ref.log_prob(x), rtol=1e-5, atol=1e-5)


def test_log_prob_matches_scipy():
    p = random_params(N=3, K=2, D=4, seed=5)
    x = torch.randn(3, 4, generator=torch.Generator().manual_seed(9))
    pi = torch.softmax(p.logit_pi, -1).double().numpy()
    for n in range(3):
        dens = sum(pi[n, k] * multivariate_normal.pdf(
            x[n].double().numpy(), mean=p.mu[n, k].double().numpy(),
            cov=np.diag(np.exp(2 * p.log_sigma[n, k].double().numpy()))) for k in range(2))
        assert float(mdn.mixture_log_prob(p, x)[n]) == pytest.approx(np.log(dens), rel=1e-5)


def test_surrogate_is_the_weighted_lower_bound():
    p = random_params(seed=1)
    x = torch.randn(6, 3)
    comp = td.Independent(td.Normal(p.mu, p.log_sigma.exp()), 1).log_prob(x.unsqueeze(1))
    want = (torch.softmax(p.logit_pi, -1) * comp).sum(-1)
    torch.testing.assert_close(mdn.surrogate_log_prob(p, x), want, rtol=1e-5, atol=1e-5)
    assert (mdn.surrogate_log_prob(p, x) <= mdn.mixture_log_prob(p, x) + 1e-5).all()
    one = mdn.MixtureParams(p.logit_pi[:, :1], p.mu[:, :1], p.log_sigma[:, :1], p.active_logit)
    torch.testing.assert_close(mdn.surrogate_log_prob(one, x), mdn.mixture_log_prob(one, x))


def test_dimension_weights_scale_each_dimensions_log_density():
    from scipy.stats import norm
    p = random_params(N=2, K=3, D=3, seed=4)
    x = torch.randn(2, 3, generator=torch.Generator().manual_seed(2))
    w = torch.tensor([1.0, 4.0, 0.0])
    mu, sd = p.mu.double().numpy(), p.log_sigma.double().exp().numpy()
    want = (norm.logpdf(x.double().numpy()[:, None, :], mu, sd) * w.double().numpy()).sum(-1)
    got = mdn.component_log_density(p, x, w)
    np.testing.assert_allclose(got.double().numpy(), want, rtol=1e-5)
    pi = torch.softmax(p.logit_pi, -1).double().numpy()
    np.testing.assert_allclose(mdn.surrogate_log_prob(p, x, w).double().numpy(),
                               (pi * want).sum(-1), rtol=1e-5)
    log_pi = torch.log_softmax(p.logit_pi, -1).double().numpy()
    np.testing.assert_allclose(mdn.mixture_log_prob(p, x, w).double().numpy(),
                               np.logaddexp.reduce(log_pi + want, axis=-1), rtol=1e-5)
    ones = torch.ones(3)
    torch.testing.assert_close(mdn.mixture_log_prob(p, x, ones), mdn.mixture_log_prob(p, x))


def test_active_log_prob_and_sampling_statistics():
    p = random_params(N=2, K=2, D=2, seed=3)
    a = torch.tensor([1.0, 0.0])
    q = torch.sigmoid(p.active_logit)
    torch.testing.assert_close(mdn.active_log_prob(p, a),
                               torch.log(torch.stack([q[0], 1 - q[1]])), rtol=1e-5, atol=1e-6)
    x, act = mdn.sample(p, 20000, torch.Generator().manual_seed(0))
    assert x.shape == (2, 20000, 2) and act.shape == (2, 20000)
    pi = torch.softmax(p.logit_pi, -1)
    mean = (pi.unsqueeze(-1) * p.mu).sum(1)
    torch.testing.assert_close(x.mean(1), mean, atol=0.05, rtol=0)
    torch.testing.assert_close(act.mean(1), q, atol=0.02, rtol=0)


def test_head_shapes_and_sigma_floor():
    head = mdn.MixtureDensityHead(7, 3, 5, min_log_sigma=-2.0)
    with torch.no_grad():
        head.proj.bias.fill_(-100.0)
    p = head(torch.zeros(2, 4, 7))
    assert p.logit_pi.shape == (2, 4, 5) and p.mu.shape == (2, 4, 5, 3)
    assert p.active_logit.shape == (2, 4) and p.log_sigma.min().item() == -2.0
    assert p.flatten().mu.shape == (8, 5, 3)


def test_sampling_temperature_sharpens_weights_and_deviations():
    # two 1-D components, weights 0.8 / 0.2, means -5 / +5, sigma 1 / 2; at tau = 0.5 the
    # weights become 0.8**2 : 0.2**2 = 0.941 : 0.059 and the deviations 0.5 / 1
    p = mdn.MixtureParams(torch.log(torch.tensor([[0.8, 0.2]])),
                          torch.tensor([[[-5.0], [5.0]]]),
                          torch.log(torch.tensor([[[1.0], [2.0]]])), torch.tensor([0.0]))
    x, _ = mdn.sample(p, 40000, torch.Generator().manual_seed(1), temperature=0.5)
    x = x[0, :, 0]
    first, second = x[x < 0], x[x > 0]
    assert len(first) / len(x) == pytest.approx(0.64 / 0.68, abs=0.005)
    assert float(first.std()) == pytest.approx(0.5, rel=0.03)
    assert float(second.std()) == pytest.approx(1.0, rel=0.08)
    x1, _ = mdn.sample(p, 40000, torch.Generator().manual_seed(1))
    assert float((x1 < 0).float().mean()) == pytest.approx(0.8, abs=0.006)  # tau 1: as is
    tiny, _ = mdn.sample(random_params(seed=2), 3, torch.Generator().manual_seed(0),
                         temperature=1e-4)
    torch.testing.assert_close(tiny, mdn.mode_frame(random_params(seed=2)).unsqueeze(1)
                               .expand_as(tiny), atol=1e-2, rtol=0)
    with pytest.raises(ValueError, match="temperature"):
        mdn.sample(p, 1, temperature=0.0)


def test_mixture_mean_by_hand_and_against_torch():
    # weights softmax(log 1, log 3) = (1/4, 3/4): mean 0.25 * (0, 4) + 0.75 * (4, 0) = (3, 1)
    p = mdn.MixtureParams(torch.log(torch.tensor([[1.0, 3.0]])),
                          torch.tensor([[[0.0, 4.0], [4.0, 0.0]]]), torch.zeros(1, 2, 2),
                          torch.zeros(1))
    torch.testing.assert_close(mdn.mixture_mean(p), torch.tensor([[3.0, 1.0]]))
    p = random_params()
    ref = td.MixtureSameFamily(td.Categorical(logits=p.logit_pi),
                               td.Independent(td.Normal(p.mu, p.log_sigma.exp()), 1))
    torch.testing.assert_close(mdn.mixture_mean(p), ref.mean)

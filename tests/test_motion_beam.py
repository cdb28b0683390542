"""Sampled motion beam and mean decoding driven by a hand-made mixture step, no model."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from motionlang.models.seq2seq.decode.motion_beam import mean_decode, sample_decode, sampled_beam
from motionlang.models.seq2seq.mdn import MixtureParams, active_log_prob, mixture_log_prob, sample

torch.set_num_threads(1)
K, D = 3, 2


def make_step(stop_at: int | None = None, p_active: float = 0.8):
    """Mixture whose means follow the previous frame; flag deterministic if stop_at given."""
    g = torch.Generator().manual_seed(7)
    offsets = torch.randn(K, D, generator=g)
    logit_pi = torch.tensor([0.5, 0.0, -1.0])

    def params_for(t: torch.Tensor, prev: torch.Tensor) -> MixtureParams:
        N = len(t)
        mu = 0.5 * prev.unsqueeze(1) + offsets + 0.1 * t.view(N, 1, 1)
        log_sigma = torch.full((N, K, D), -1.0) + 0.05 * t.view(N, 1, 1)
        if stop_at is None:
            act = torch.full((N,), float(np.log(p_active / (1 - p_active))))
        else:
            act = torch.where(t < stop_at, torch.tensor(20.0), torch.tensor(-20.0))
        return MixtureParams(logit_pi.expand(N, K).clone(), mu, log_sigma, act)

    def step(state, prev):
        return params_for(state, prev), state + 1

    return step, params_for


def replay_score(params_for, frames: np.ndarray) -> float:
    """Log likelihood of a whole hypothesis, recomputed frame by frame."""
    prev = torch.zeros(1, D)
    total = 0.0
    for t, f in enumerate(torch.tensor(frames)):
        p = params_for(torch.tensor([t]), prev)
        a = torch.tensor([0.0 if t == len(frames) - 1 else 1.0])
        total += float(mixture_log_prob(p, f[None]) + active_log_prob(p, a))
        prev = f[None]
    return total


@pytest.mark.parametrize("seed", range(4))
def test_sampled_beam_scores_are_log_likelihoods(seed):
    step, params_for = make_step(p_active=0.7)
    B, W = 2, 3
    res = sampled_beam(step, torch.zeros(B, dtype=torch.long), batch_size=B, width=W,
                       max_frames=6, samples=4, dim=D,
                       generator=torch.Generator().manual_seed(seed))
    assert len(res) == B
    for hyps in res:
        assert 1 <= len(hyps) <= W
        assert [h.score for h in hyps] == sorted((h.score for h in hyps), reverse=True)
        for h in hyps:
            assert h.frames.shape[1] == D and 1 <= len(h.frames) <= 6
            assert h.frames.dtype == np.float32
            assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)


def test_deterministic_flag_fixes_the_length():
    step, _ = make_step(stop_at=4)
    res = sampled_beam(step, torch.zeros(1, dtype=torch.long), batch_size=1, width=3,
                       max_frames=20, samples=5, dim=D, generator=torch.Generator().manual_seed(0))
    assert all(len(h.frames) == 5 for h in res[0])
    assert len(res[0]) == 3
    # distinct samples: three different motions
    assert not np.allclose(res[0][0].frames, res[0][1].frames)
    mean = mean_decode(step, torch.zeros(2, dtype=torch.long), batch_size=2, max_frames=20,
                       dim=D)
    assert [len(h.frames) for h in mean] == [5, 5]
    capped = mean_decode(step, torch.zeros(1, dtype=torch.long), batch_size=1, max_frames=3,
                         dim=D)
    assert len(capped[0].frames) == 3


def test_one_step_keeps_the_most_likely_samples():
    # max_frames=1: every candidate finishes at once, so the beam must return exactly the
    # W most likely of the S drawn candidates (same generator seed -> same draws).
    step, params_for = make_step(p_active=0.5)
    W, S = 2, 6
    res = sampled_beam(step, torch.zeros(1, dtype=torch.long), batch_size=1, width=W,
                       max_frames=1, samples=S, dim=D, generator=torch.Generator().manual_seed(3))
    p = params_for(torch.zeros(1, dtype=torch.long), torch.zeros(1, D))
    x, _ = sample(p, S, torch.Generator().manual_seed(3))
    rep = MixtureParams(p.logit_pi.expand(S, K), p.mu.expand(S, K, D),
                        p.log_sigma.expand(S, K, D), p.active_logit.expand(S))
    ll = mixture_log_prob(rep, x[0]) + active_log_prob(rep, torch.zeros(S))
    order = ll.argsort(descending=True)[:W]
    np.testing.assert_allclose([h.score for h in res[0]], ll[order].numpy(), rtol=1e-5)
    np.testing.assert_allclose(np.stack([h.frames[0] for h in res[0]]), x[0, order].numpy())


def test_mean_decode_follows_heaviest_component():
    step, params_for = make_step(stop_at=2)
    h = mean_decode(step, torch.zeros(1, dtype=torch.long), batch_size=1, max_frames=10,
                    start=torch.zeros(D))[0]
    prev = torch.zeros(1, D)
    for t, f in enumerate(h.frames):
        p = params_for(torch.tensor([t]), prev)
        np.testing.assert_allclose(f, p.mu[0, 0].numpy(), rtol=1e-6)   # component 0 heaviest
        prev = torch.tensor(f)[None]
    assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)


def test_min_frames_holds_the_flag():
    step, params_for = make_step(p_active=0.2)
    res = sampled_beam(step, torch.zeros(1, dtype=torch.long), batch_size=1, width=3,
                       max_frames=10, samples=4, min_frames=4, dim=D,
                       generator=torch.Generator().manual_seed(2))[0]
    assert all(len(h.frames) >= 4 for h in res)
    for h in res:
        assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)
    mean = mean_decode(step, torch.zeros(1, dtype=torch.long), batch_size=1, max_frames=10,
                       dim=D, min_frames=3)[0]
    assert len(mean.frames) == 3             # P(active) = 0.2 < 0.5 ends it right after


def test_length_norm_ranks_by_log_likelihood_per_frame():
    step, params_for = make_step(p_active=0.6)
    kw = dict(batch_size=1, width=4, max_frames=8, samples=4, dim=D)
    total = sampled_beam(step, torch.zeros(1, dtype=torch.long),
                         generator=torch.Generator().manual_seed(4), **kw)[0]
    norm = sampled_beam(step, torch.zeros(1, dtype=torch.long), length_norm=True,
                        generator=torch.Generator().manual_seed(4), **kw)[0]
    per_frame = [h.score / len(h.frames) for h in norm]
    assert per_frame == sorted(per_frame, reverse=True)
    for h in norm:                                   # scores stay totals
        assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)
    best_total = max(h.score / len(h.frames) for h in total)
    assert per_frame[0] >= best_total - 1e-9         # same draws, better per-frame pick


def test_sample_decode_draws_independent_motions_ended_by_the_flag():
    step, params_for = make_step(stop_at=4)
    hyps = sample_decode(step, torch.zeros(1, dtype=torch.long), width=3, max_frames=10,
                         dim=D, generator=torch.Generator().manual_seed(5))
    assert len(hyps) == 3
    assert all(len(h.frames) == 5 for h in hyps)       # flag on for t < 4, off at t = 4
    assert [h.score for h in hyps] == sorted((h.score for h in hyps), reverse=True)
    assert not np.allclose(hyps[0].frames, hyps[1].frames)  # independent draws
    for h in hyps:
        assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)
    # the draws are those of the mixture: replaying the RNG gives the same first frames
    g = torch.Generator().manual_seed(5)
    first = sample(params_for(torch.zeros(3, dtype=torch.long), torch.zeros(3, D)), 1, g)[0]
    assert sorted(map(tuple, first[:, 0].numpy().round(5))) == \
        sorted(tuple(h.frames[0].round(5)) for h in hyps)
    again = sample_decode(step, torch.zeros(1, dtype=torch.long), width=3, max_frames=10,
                          dim=D, generator=torch.Generator().manual_seed(5))
    assert [h.score for h in again] == [h.score for h in hyps]


def test_sample_decode_length_norm_ranks_per_frame():
    # the flag goes off once the previous frame's first value is positive: lengths differ
    def step(t, prev):
        N = len(prev)
        mu = torch.zeros(N, K, D)
        act = torch.where((t > 0) & (prev[:, 0] > 0), torch.tensor(-20.0), torch.tensor(20.0))
        return MixtureParams(torch.zeros(N, K), mu, torch.zeros(N, K, D), act), t + 1
    state = torch.zeros(1, dtype=torch.long)
    for norm in (False, True):
        hyps = sample_decode(step, state, width=6, max_frames=12, dim=D, length_norm=norm,
                             generator=torch.Generator().manual_seed(3))
        assert len({len(h.frames) for h in hyps}) > 1          # the test needs mixed lengths
        key = [h.score / len(h.frames) if norm else h.score for h in hyps]
        assert key == sorted(key, reverse=True)


def test_sample_decode_temperature_draws_from_the_sharpened_mixture():
    step, params_for = make_step(stop_at=4)
    hyps = sample_decode(step, torch.zeros(1, dtype=torch.long), width=3, max_frames=10,
                         dim=D, temperature=0.3, generator=torch.Generator().manual_seed(5))
    g = torch.Generator().manual_seed(5)
    first = sample(params_for(torch.zeros(3, dtype=torch.long), torch.zeros(3, D)), 1, g,
                   temperature=0.3)[0]
    assert sorted(map(tuple, first[:, 0].numpy().round(5))) == \
        sorted(tuple(h.frames[0].round(5)) for h in hyps)
    for h in hyps:                         # scored under the model's own distribution
        assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)


@pytest.mark.parametrize("sampled", [False, True])
def test_a_given_first_frame_is_kept_and_continued_from(sampled):
    """``first``: frame 0 is the given one, the next frames follow the mixture that reads
    it (the means follow the previous frame), and the score is the replayed likelihood."""
    step, params_for = make_step(stop_at=4)
    first = torch.tensor([3.0, -2.0])
    if sampled:
        hyps = sample_decode(step, torch.zeros(1, dtype=torch.long), width=2, max_frames=10,
                             dim=D, first=first, generator=torch.Generator().manual_seed(0))
    else:
        hyps = mean_decode(step, torch.zeros(1, dtype=torch.long), batch_size=1,
                           max_frames=10, dim=D, first=first)
    for h in hyps:
        assert len(h.frames) == 5
        np.testing.assert_array_equal(h.frames[0], first.numpy())
        assert h.score == pytest.approx(replay_score(params_for, h.frames), abs=1e-3)
    if not sampled:   # the heaviest component's mean given frame 0 = (3, -2)
        p = params_for(torch.tensor([1]), first[None])
        np.testing.assert_allclose(hyps[0].frames[1], p.mu[0, 0].numpy(), rtol=1e-6)
        plain = mean_decode(step, torch.zeros(1, dtype=torch.long), batch_size=1,
                            max_frames=10, dim=D)[0]
        assert not np.allclose(plain.frames[1], hyps[0].frames[1])

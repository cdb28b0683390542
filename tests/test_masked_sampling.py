"""The masked family's parts that need no model: the cosine masking schedule, the training
mask and corruption, iterative decoding against a hand-made predictor, the EMA residual
quantiser (dead-code reset, residuals), and the in-betweening arithmetic (kept tokens,
gaps, offset blending, the linear baseline) by hand."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from motionlang.models.masked import sampling
from motionlang.models.masked.inbetween import blend, gaps, kept_tokens, linear_fill
from motionlang.models.masked.tokenizer import ResidualQuantizer, pad_frames

torch.set_num_threads(1)


def test_the_cosine_schedule_masks_all_then_none():
    t = torch.linspace(0, 1, 11)
    r = sampling.mask_ratio(t)
    assert r[0] == 1.0 and abs(float(r[-1])) < 1e-6
    assert bool((r[1:] <= r[:-1]).all())                         # never unmasks backwards
    assert float(sampling.mask_ratio(0.5)) == pytest.approx(math.cos(math.pi / 4))


def test_the_training_mask_stays_inside_each_motion_and_masks_at_least_one():
    torch.manual_seed(0)
    valid = torch.arange(12)[None] < torch.tensor([12, 5, 1])[:, None]
    for _ in range(50):
        m = sampling.training_mask(valid)
        assert not (m & ~valid).any()
        assert (m.sum(1) >= 1).all() and (m.sum(1) <= valid.sum(1)).all()
    # over many draws the masked fraction is the schedule's mean, 2/pi
    big = torch.ones(4000, 50, dtype=torch.bool)
    frac = sampling.training_mask(big).float().mean()
    assert float(frac) == pytest.approx(2 / math.pi, abs=0.02)


def test_corruption_is_80_10_10_on_masked_positions_only():
    torch.manual_seed(0)
    tokens = torch.randint(0, 50, (200, 100))
    masked = torch.rand(200, 100) < 0.5
    out = sampling.corrupt(tokens, masked, codes=50, mask_id=50)
    assert torch.equal(out[~masked], tokens[~masked])
    share = (out[masked] == 50).float().mean()
    assert float(share) == pytest.approx(0.8, abs=0.01)
    assert float((out[masked] == tokens[masked]).float().mean()) >= 0.1 - 0.01


class Prefers:
    """A predictor that wants code (position mod K), more surely the lower the position
    (so iteration order is known), and ignores the condition."""

    def __init__(self, K: int = 7):
        self.K, self.calls = K, []

    def __call__(self, tokens, drop):
        self.calls.append((tokens.clone(), drop))
        B, L = tokens.shape
        logits = torch.zeros(B, L, self.K)
        pos = torch.arange(L)
        logits[:, pos, pos % self.K] = 3.0 - 0.2 * pos.float()
        return logits


def test_iterative_decoding_follows_the_schedule_and_keeps_given_tokens():
    pred = Prefers()
    valid = torch.arange(10)[None] < torch.tensor([10, 6])[:, None]
    g = torch.Generator().manual_seed(0)
    out = sampling.decode_base(pred, valid, mask_id=7, steps=4, guidance=1.0,
                               temperature=0.0, top_k=0, generator=g)
    pos = torch.arange(10)
    assert torch.equal(out[0], pos % 7) and torch.equal(out[1, :6], pos[:6] % 7)
    assert (out[1, 6:] == 0).all()                                # padding: code 0
    # after step s, floor(cos(pi/2 s/4) * 10) tokens of row 0 were masked again
    masked_seen = [int((t[0] == 7).sum()) for t, _ in pred.calls]
    assert masked_seen == [10] + [math.floor(math.cos(math.pi / 2 * s / 4) * 10)
                                  for s in (1, 2, 3)]
    # the most confident (lowest positions) are fixed first
    assert (pred.calls[2][0][0, :3] != 7).all() and (pred.calls[2][0][0, 3:] == 7).all()
    # kept tokens are never masked or changed
    known = torch.full((2, 10), 3)
    kept = torch.zeros(2, 10, dtype=torch.bool)
    kept[:, :4] = True
    out = sampling.decode_base(Prefers(), valid, 7, steps=3, guidance=1.0, temperature=0.0,
                               top_k=0, generator=g, known=known, kept=kept)
    assert (out[:, :4] == 3).all() and torch.equal(out[0, 4:], pos[4:] % 7)


def test_guidance_mixes_the_conditioned_and_unconditioned_logits():
    calls = []

    def fn(tokens, drop):   # conditioned rows give 1, unconditioned 0
        calls.append(len(tokens))
        if drop is None:
            return torch.ones(len(tokens), 2, 3)
        return (~drop).float()[:, None, None].expand(len(tokens), 2, 3)
    tokens = torch.zeros(1, 2, dtype=torch.long)
    assert torch.equal(sampling.guided(fn, tokens, 4.0), torch.full((1, 2, 3), 4.0))
    assert torch.equal(sampling.guided(fn, tokens, 1.0), torch.ones(1, 2, 3))
    assert calls == [2, 1]   # guidance: both halves in one pass of 2B rows
    logits = torch.tensor([[[0.0, 1.0, 5.0, 2.0]]])
    codes, probs = sampling.pick(logits, 1.0, 1, torch.Generator().manual_seed(0))
    assert int(codes) == 2 and float(probs) == pytest.approx(1.0)    # top-1: no choice


def test_the_residual_quantiser_codes_what_is_left_and_resets_dead_codes():
    torch.manual_seed(0)
    rq = ResidualQuantizer(quantizers=3, codes=4, dim=2, decay=0.5, dropout=0.0)
    z = torch.randn(2, 8, 2)
    mask = torch.ones(2, 8, dtype=torch.bool)
    rq.train()
    q, idx, commit = rq(z, mask)
    assert bool(rq.ready) and idx.shape == (2, 8, 3) and commit.ndim == 0
    rq.eval()
    q, idx, _ = rq(z, mask)
    # the quantised latent is the sum of one code of each codebook
    manual = sum(rq.codebooks[k][idx[..., k]] for k in range(3))
    assert torch.allclose(q, manual, atol=1e-6) and torch.allclose(rq.lookup(idx), manual)
    # more codebooks leave less: the error never grows with k
    errs = [float((rq.lookup(idx[..., :k]) - z).norm()) for k in (1, 2, 3)]
    assert errs[0] >= errs[1] - 1e-6 >= errs[2] - 2e-6
    # a code far from every vector is reset onto one of the batch within a few updates
    rq.train()
    rq.codebooks[0, 3] = torch.tensor([100.0, 100.0])
    rq.sums[0, 3] = rq.codebooks[0, 3]
    for _ in range(3):
        rq(z, mask)
    assert float(rq.codebooks[0, 3].abs().max()) < 10.0


def test_pad_frames_repeats_the_last_frame_to_whole_tokens():
    x = torch.arange(10.0).reshape(1, 5, 2)
    p = pad_frames(x)
    assert p.shape == (1, 8, 2) and torch.equal(p[0, 5:], x[0, -1:].expand(3, 2))
    assert pad_frames(x[:, :4]) is not None and pad_frames(x[:, :4]).shape == (1, 4, 2)


def test_kept_tokens_and_gaps_by_hand():
    keep = np.array([1, 1, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 1, 1], dtype=bool)
    # tokens: frames 0-3 kept; 4-7 partly; 8-11 partly; 12-13 (+2 padding) kept
    assert kept_tokens(keep).tolist() == [True, False, False, True]
    assert gaps(keep) == [(6, 9)]
    assert gaps(np.array([0, 0, 1, 0], dtype=bool)) == [(0, 2), (3, 4)]


def test_blend_keeps_kept_frames_and_meets_them_at_both_ends():
    T = 10
    src = np.zeros((T, 21, 3))
    src[:, :, 0] = np.arange(T)[:, None]                        # moves 1 m a frame along x
    gen = src + np.array([0.0, 0.0, 5.0])                        # off by 5 m along z
    keep = np.ones(T, dtype=bool)
    keep[3:7] = False
    out = blend(gen, src, keep)
    assert np.array_equal(out[keep], src[keep])
    np.testing.assert_allclose(out, src, atol=1e-12)            # a constant offset is removed
    # an offset that differs at the two ends is spread linearly over the gap
    gen2 = gen.copy()
    gen2[7:] += np.array([0.0, 0.0, 5.0])
    out2 = blend(gen2, src, keep)
    z = out2[3:7, 0, 2] - src[3:7, 0, 2]
    np.testing.assert_allclose(np.diff(z), np.diff(z)[0])
    lin = linear_fill(src, keep)
    np.testing.assert_allclose(lin, src)                         # straight line: exact
    assert np.array_equal(linear_fill(src, np.zeros(T, dtype=bool)), src)

"""The L2M's foot-contact term: foot steps read from position features match the decoded
motion's, the loss measures a planted foot's slide in m/s and nothing else, and the model
adds it (weighted) to its loss and trains through it."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import torch

from motionlang.errors import MotionlangError
from motionlang.features import root as rootlib
from motionlang.features.joint_map import TOES
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import PositionFeatures, split_global
from motionlang.models.frame_losses import foot_contact_loss, foot_steps
from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
from motionlang.models.seq2seq.losses import expected_foot_loss, fed_foot_contact_loss
from motionlang.models.seq2seq.mdn import mixture_mean

FPS = 12.5


def walking_body(T=20, seed=0) -> np.ndarray:
    """(T, 21, 3) global positions: a rigid random body turning and travelling, feet on
    y = 0 (both toes at height 0.02), hips across x so that it has a heading."""
    rng = np.random.default_rng(seed)
    pose = rng.normal(0, 0.2, (21, 3))
    pose[:, 1] = np.abs(pose[:, 1]) + 0.3
    pose[0] = [0.0, 0.9, 0.0]
    pose[11], pose[16] = [-0.1, 0.9, 0.0], [0.1, 0.9, 0.0]     # LH, RH
    pose[5], pose[8] = [-0.2, 1.4, 0.0], [0.2, 1.4, 0.0]       # LS, RS
    pose[list(TOES), 1] = 0.02
    yaw = np.cumsum(rng.normal(0, 0.1, T))
    ground = np.cumsum(rng.normal(0, 0.05, (T, 2)), axis=0)
    p = rootlib.from_heading(np.broadcast_to(pose, (T, 21, 3)), yaw[:, None])
    p[..., 0] += ground[:, None, 0]
    p[..., 2] += ground[:, None, 1]
    return p


def raw_features(p21: np.ndarray) -> torch.Tensor:
    local, v, dyaw, _ = split_global(p21)
    return torch.tensor(np.concatenate([local.reshape(len(p21), -1), v, dyaw[:, None]], 1),
                        dtype=torch.float64).unsqueeze(0)


def test_foot_steps_are_the_decoded_motions_steps_in_the_previous_heading_frame():
    p = walking_body()
    local, v, dyaw, _ = split_global(p)
    yaw = rootlib.integrate(v, dyaw, (0, 0, 0))[1]
    yaw = yaw - yaw[0] + np.arctan2(*_forward(p[0]))   # the body's own heading
    want = rootlib.to_heading(np.diff(p[:, list(TOES)], axis=0), yaw[:-1, None])[..., [0, 2]]
    got = foot_steps(raw_features(p), TOES)[0].numpy()
    np.testing.assert_allclose(got, want, atol=1e-9)
    assert np.abs(want).max() > 0.01          # the feet do travel here


def _forward(p0):
    from motionlang.features.positions import facing_yaw
    yaw = facing_yaw(p0[None])[0]
    return np.sin(yaw), np.cos(yaw)


def planted_walk(T=12) -> np.ndarray:
    """A body standing still, its left toe down throughout, its right toe 0.3 m up."""
    p = walking_body(T)[:1].repeat(T, axis=0)
    p[:, TOES[1], 1] = 0.3
    return p


def test_a_planted_foot_that_slides_costs_its_speed_and_a_lifted_one_nothing():
    target = raw_features(planted_walk())
    mask = torch.ones(1, target.shape[1])
    assert float(foot_contact_loss(target, target, mask, TOES, FPS)) < 1e-3   # eps only
    slid = target.clone()
    slid[..., 64] += 0.02                        # the whole body glides 2 cm a frame forward
    got = float(foot_contact_loss(slid, target, mask, TOES, FPS))
    assert got == pytest.approx(0.02 * FPS, rel=1e-4)   # only the left toe is down: 0.25 m/s
    lifted = target.clone()
    lifted[..., 3 * TOES[0] + 1] = 0.3           # no toe of the reference is down
    assert float(foot_contact_loss(slid, lifted, mask, TOES, FPS)) == 0.0
    # padding frames count for nothing; a fast reference foot is not a contact
    pad = torch.zeros(1, target.shape[1])
    assert float(foot_contact_loss(slid, target, pad, TOES, FPS)) == 0.0
    fast = target.clone()
    fast[..., 64] += 0.1                         # 1.25 m/s: a foot that only passes low
    assert float(foot_contact_loss(slid, fast, mask, TOES, FPS)) == 0.0


def test_own_contacts_are_read_from_the_prediction_not_the_reference():
    """down="own": the contact test runs on the predicted frames; the reference only sets
    the shapes. A slide of the prediction's own low toe costs its speed even where the
    reference's toes are up, and a prediction whose toes are up costs nothing."""
    target = raw_features(planted_walk())
    mask = torch.ones(1, target.shape[1])
    slid = target.clone()
    slid[..., 64] += 0.02                        # 0.25 m/s; its left toe low, the right up
    lifted = target.clone()
    lifted[..., 3 * TOES[0] + 1] = 0.3           # the reference with both toes up
    assert float(foot_contact_loss(slid, lifted, mask, TOES, FPS)) == 0.0
    got = float(foot_contact_loss(slid, lifted, mask, TOES, FPS, down="own"))
    assert got == pytest.approx(0.02 * FPS, rel=1e-4)
    slid_up = slid.clone()
    slid_up[..., 3 * TOES[0] + 1] = 0.3          # the prediction's toes up: no contact
    assert float(foot_contact_loss(slid_up, target, mask, TOES, FPS, down="own")) == 0.0
    # the gradient reaches the prediction's steps through the speed of its own planted toe
    pred = slid.clone().requires_grad_(True)
    foot_contact_loss(pred, lifted, mask, TOES, FPS, down="own").backward()
    assert float(pred.grad[..., 64].abs().sum()) > 0                     # root step
    with pytest.raises(ValueError, match="down"):
        foot_contact_loss(slid, target, mask, TOES, FPS, down="both")


def test_the_l2m_reads_its_own_contacts_when_asked():
    from motionlang.models.seq2seq import mdn
    still = raw_features(planted_walk()).float()           # its left toe down, right up
    lifted = still.clone()
    lifted[..., 3 * TOES[0] + 1] = 0.3                     # the reference: both toes up
    model = _tiny_positions_l2m(foot_weight=1.0, foot_down="own")
    # a normaliser centred on the standing pose with a small spread: the untrained model's
    # frames stay near it, the left toe low and slow
    mu = still[0, 0].double().numpy()
    model.features.normalizer = Normalizer(mean=mu, std=np.full(66, 0.02))
    target = (lifted - torch.tensor(mu, dtype=torch.float32)) / 0.02
    batch = {"motion": target, "motion_lengths": torch.tensor([target.shape[1]]),
             "tokens": torch.tensor([[1, 4, 5, 2]]), "token_lengths": torch.tensor([4])}
    model.eval()
    with torch.no_grad():
        out = model.loss(batch)
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        mean = mdn.mixture_mean(p.flatten()).reshape(target.shape) * 0.02 + torch.tensor(
            mu, dtype=torch.float32)
        mask = torch.ones(1, target.shape[1])
        want = foot_contact_loss(mean, lifted, mask, TOES, FPS, down="own")
        other = foot_contact_loss(mean, lifted, mask, TOES, FPS)
    assert float(want) > 0 and float(other) == 0.0        # its own toe is down, not the ref's
    torch.testing.assert_close(out["foot"], want)
    with pytest.raises(MotionlangError, match="foot_down"):
        L2MConfig(vocab_size=9, n_features=66, foot_down="theirs")
    with pytest.raises(MotionlangError, match="foot_step input"):
        L2MConfig(vocab_size=9, n_features=66, foot_down="own", foot_step="input")


def test_its_gradient_is_finite_where_the_foot_does_not_move():
    target = raw_features(planted_walk())
    pred = target.clone().requires_grad_(True)
    foot_contact_loss(pred, target, torch.ones(1, target.shape[1]), TOES, FPS).backward()
    assert torch.isfinite(pred.grad).all()


def _tiny_positions_l2m(**options) -> LanguageToMotion:
    feats = PositionFeatures()
    feats.normalizer = Normalizer(mean=np.zeros(66), std=np.full(66, 0.5))
    torch.manual_seed(0)
    cfg = L2MConfig(vocab_size=9, n_features=66, embed_dim=8, enc_hidden=8, enc_layers=1,
                    dec_hidden=16, dec_layers=1, n_components=2, max_frames=20, **options)
    return LanguageToMotion(cfg, vocab=[f"w{i}" for i in range(9)], features=feats)


def test_the_l2m_adds_the_term_with_its_weight_and_learns_through_it():
    from motionlang.models.seq2seq import mdn
    target = raw_features(planted_walk()).float() / 0.5        # normalised (std 0.5)
    batch = {"motion": target, "motion_lengths": torch.tensor([target.shape[1]]),
             "tokens": torch.tensor([[1, 4, 5, 2]]), "token_lengths": torch.tensor([4])}
    model = _tiny_positions_l2m()
    model.eval()
    with torch.no_grad():
        base = model.loss(batch)
        assert "foot" not in base                              # off by default
        model.config.foot_weight = 2.0
        out = model.loss(batch)
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        mean = mdn.mixture_mean(p.flatten()).reshape(target.shape) * 0.5
        want = foot_contact_loss(mean, target * 0.5, torch.ones(1, target.shape[1]), TOES, FPS)
    assert float(want) > 0
    torch.testing.assert_close(out["foot"], want)
    torch.testing.assert_close(out["loss"], base["loss"] + 2.0 * want)
    # trained on the term alone (its weight large), the planted toe's slide goes down
    model = _tiny_positions_l2m(foot_weight=1.0)
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    model.train()
    valid = torch.ones(1, target.shape[1], dtype=torch.bool)

    def term():
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"]).flatten()
        expected = mixture_mean(p).reshape(batch["motion"].shape)
        return expected_foot_loss(expected, batch["motion"], valid, None, model.features)
    first = float(term())
    for _ in range(60):
        opt.zero_grad()
        term().backward()
        opt.step()
    assert float(term()) < 0.5 * first


def test_the_term_needs_position_features():
    model = _tiny_positions_l2m()
    with pytest.raises(MotionlangError, match="foot_weight"):
        LanguageToMotion(replace(model.config, foot_weight=1.0, n_features=5,
                                 plan_parts=0), features=model.features)
    with pytest.raises(MotionlangError, match="foot_weight"):
        L2MConfig(vocab_size=9, n_features=66, foot_weight=-1.0)
    bare = LanguageToMotion(replace(model.config, foot_weight=1.0))   # no features at all
    batch = {"motion": torch.zeros(1, 4, 66), "motion_lengths": torch.tensor([4]),
             "tokens": torch.tensor([[1, 4, 2]]), "token_lengths": torch.tensor([3])}
    with pytest.raises(MotionlangError, match="position features"):
        bare.loss(batch)


def test_input_steps_go_from_the_frame_fed_to_the_expected_frame():
    from motionlang.models.seq2seq import mdn
    target = raw_features(planted_walk()).float() / 0.5
    T = target.shape[1]
    batch = {"motion": target, "motion_lengths": torch.tensor([T]),
             "tokens": torch.tensor([[1, 4, 5, 2]]), "token_lengths": torch.tensor([4])}
    model = _tiny_positions_l2m(foot_weight=1.0, foot_step="input")
    model.eval()   # teacher forced: the frame fed at step t is the true frame t-1
    with torch.no_grad():
        got = model.loss(batch)["foot"]
        mean = mdn.mixture_mean(model(batch["tokens"], batch["token_lengths"],
                                      target).flatten()).reshape(target.shape) * 0.5
    true = target * 0.5
    pairs = torch.stack([true[0, :-1], mean[0, 1:]], dim=1)        # (T-1, 2, 66)
    want = foot_contact_loss(pairs, torch.stack([true[0, :-1], true[0, 1:]], dim=1),
                             torch.ones(T - 1, 2), TOES, FPS)
    torch.testing.assert_close(got, want)
    expected = _tiny_positions_l2m(foot_weight=1.0)
    expected.eval()
    with torch.no_grad():
        assert float(expected.loss(batch)["foot"]) != pytest.approx(float(got))
    # a scheduled-sampling model measures from its own fed frames, and trains through it
    rolled = _tiny_positions_l2m(foot_weight=1.0, foot_step="input", rollout=1.0)
    rolled.eval()   # validated as trained: its own frames, a fixed RNG
    with torch.no_grad():
        got = rolled.loss(batch)["foot"]
        params, fed = rolled.rollout_forward(batch["tokens"], batch["token_lengths"], target,
                                             1.0, return_fed=True)
    assert not torch.allclose(fed[:, 1:], target[:, :-1])      # not the true frames
    pred = mdn.mixture_mean(params.flatten()).reshape(target.shape) * 0.5
    want = fed_foot_contact_loss(fed * 0.5, pred, true, torch.ones(1, T), TOES, FPS)
    torch.testing.assert_close(got, want)
    rolled.train()
    out = rolled.loss(batch)
    out["loss"].backward()
    assert float(out["foot"]) > 0
    assert all(torch.isfinite(q.grad).all() for q in rolled.parameters() if q.grad is not None)
    with pytest.raises(MotionlangError, match="foot_step"):
        _tiny_positions_l2m(foot_step="sideways")

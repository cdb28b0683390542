"""The shared trainer: resume equals uninterrupted, checkpoints, plots, 2-process DDP."""
from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from helpers.trainer_tiny import TinyReg, collate, ddp_config, make_data
from motionlang.errors import MotionlangError
from motionlang.training.trainer import TrainConfig, Trainer

torch.set_num_threads(1)


def config(out, epochs, **kw) -> TrainConfig:
    return TrainConfig(**{"epochs": epochs, "batch_size": 8, "lr": 5e-3, "seed": 11,
                          "grad_clip": 5.0, "out_dir": str(out), "plot": False,
                          "progress": False, **kw})


def run(out, epochs, resume=False, init_seed=0, fail_after=None, **kw):
    torch.manual_seed(init_seed)
    model = TinyReg(dropout=0.3, fail_after=fail_after)
    trainer = Trainer(model, make_data(), collate, config(out, epochs, **kw),
                      val_set=make_data(12, 1),
                      length_of=lambda item: int(10 * abs(float(item[0][0]))))  # stand-in length
    hist = trainer.fit(resume=resume)
    return model, trainer, hist


def assert_same_weights(a, b):
    for (na, pa), (nb, pb) in zip(a.state_dict().items(), b.state_dict().items()):
        assert na == nb and torch.equal(pa, pb), na


def test_resume_at_epoch_end_equals_uninterrupted(tmp_path):
    full, _, hist_full = run(tmp_path / "full", 4)
    run(tmp_path / "part", 2)
    # a differently initialised model: everything must come from last.pt
    resumed, _, hist_res = run(tmp_path / "part", 4, resume=True, init_seed=99)
    assert_same_weights(full, resumed)
    assert [h["train"] for h in hist_full] == [h["train"] for h in hist_res]
    assert [h["val"] for h in hist_full] == [h["val"] for h in hist_res]
    assert len(hist_res) == 4


def test_resume_after_mid_epoch_interruption(tmp_path):
    full, _, hist_full = run(tmp_path / "full", 3, checkpoint_every=2)
    with pytest.raises(KeyboardInterrupt):          # dies inside epoch 2 (5 batches/epoch)
        run(tmp_path / "cut", 3, checkpoint_every=2, fail_after=8)
    ck = torch.load(tmp_path / "cut" / "last.pt", weights_only=True)
    assert (ck["epoch"], ck["batch"], ck["step"]) == (1, 3, 8)
    resumed, _, hist_res = run(tmp_path / "cut", 3, resume=True, init_seed=5, checkpoint_every=2)
    assert_same_weights(full, resumed)
    assert [h["train"] for h in hist_full] == [h["train"] for h in hist_res]


def test_outputs_and_learning(tmp_path):
    model, trainer, hist = run(tmp_path, 6, plot=True, lr=3e-2)
    assert hist[-1]["train"]["loss"] < 0.7 * hist[0]["train"]["loss"]
    assert set(hist[0]["val"]) == {"loss", "mae"} and hist[0]["seq_per_s"] > 0
    saved = json.loads((tmp_path / "history.json").read_text())
    assert [h["epoch"] for h in saved] == list(range(1, 7))
    png = (tmp_path / "loss_curve.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 2000
    best = torch.load(tmp_path / "best.pt", weights_only=True)
    vals = [h["val"]["loss"] for h in hist]
    assert best["best"] == min(vals) and best["epoch"] == vals.index(min(vals)) + 1
    last = torch.load(tmp_path / "last.pt", weights_only=True)
    for k, v in model.state_dict().items():
        assert torch.equal(last["model"]["state_dict"][k], v)
    assert not list(tmp_path.glob(".*tmp*"))           # no temporary files left behind


def test_trains_a_seq2seq_model_and_checkpoint_loads(tmp_path):
    from helpers.seq2seq import make_batch, outputs, tiny
    from motionlang.models.seq2seq.m2l import MotionToLanguage
    batch = make_batch()
    items = [{k: v[i] for k, v in batch.items()} for i in range(4)]

    def collate_m2l(xs):
        return {k: torch.stack([x[k] for x in xs]) for k in xs[0]}

    model = tiny("m2l", True)
    Trainer(model, items, collate_m2l, config(tmp_path, 2, batch_size=2)).fit()
    loaded = MotionToLanguage.load(tmp_path / "last.pt")
    torch.testing.assert_close(outputs(loaded, batch), outputs(model, batch), rtol=0, atol=0)


def test_two_process_ddp_matches_single_process(tmp_path):
    worker = Path(__file__).parent / "helpers" / "trainer_tiny.py"
    for _ in range(2):
        proc = subprocess.run(
            [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node",
             "2", str(worker), str(tmp_path)], capture_output=True, text=True, timeout=120,
            env={**__import__("os").environ, "OMP_NUM_THREADS": "1"})
        # gloo can abort a rank while tearing its connections down after the run (rarely,
        # despite finish_distributed's barrier): that, and only that, is tried once more
        if proc.returncode == 0 or "SIGABRT" not in proc.stderr:
            break
    assert proc.returncode == 0, proc.stderr[-3000:]
    r0 = torch.load(tmp_path / "rank0.pt", weights_only=True)
    r1 = torch.load(tmp_path / "rank1.pt", weights_only=True)
    for k in r0:
        assert torch.equal(r0[k], r1[k]), k                # ranks never diverge
    torch.manual_seed(0)
    single = TinyReg()
    trainer = Trainer(single, make_data(41), collate, ddp_config(tmp_path / "single"),
                      val_set=make_data(16, 1))
    hist = trainer.fit()
    start = TinyReg()
    moved = 0.0
    for k, v in single.state_dict().items():
        torch.testing.assert_close(r0[k], v, rtol=1e-4, atol=1e-5)
        moved += float((v - start.state_dict()[k]).abs().sum())
    assert moved > 0.1                                   # training really happened
    ddp_hist = torch.load(tmp_path / "history.pt", weights_only=False)
    assert ddp_hist[-1]["val"]["loss"] == pytest.approx(hist[-1]["val"]["loss"], rel=1e-4)
    assert (tmp_path / "run" / "last.pt").exists()


def test_length_buckets_group_similar_lengths_and_cover_every_item(tmp_path):
    items = make_data(40)
    lengths = [(7 * i) % 40 for i in range(40)]          # a permutation of 0..39
    cfg = config(tmp_path, 1, length_buckets=5)          # pools of 5 batches of 8 = all 40
    t = Trainer(TinyReg(), items, collate, cfg, length_of=lambda it: lengths[
        next(i for i, x in enumerate(items) if x is it)])
    batches = t._batches(0)
    assert sorted(i for b in batches for i in b) == list(range(40))
    spans = sorted((min(lengths[i] for i in b), max(lengths[i] for i in b)) for b in batches)
    assert spans == [(0, 7), (8, 15), (16, 23), (24, 31), (32, 39)]   # one pool: sorted
    assert t._batches(0) == batches and t._batches(1) != batches       # (seed, epoch) only
    plain = Trainer(TinyReg(), items, collate, config(tmp_path, 1))._batches(0)
    assert max(max(lengths[i] for i in b) - min(lengths[i] for i in b) for b in plain) > 7


def test_length_buckets_resume_equals_uninterrupted(tmp_path):
    full, _, _ = run(tmp_path / "full", 3, length_buckets=2)
    run(tmp_path / "part", 1, length_buckets=2)
    resumed, _, _ = run(tmp_path / "part", 3, resume=True, init_seed=5, length_buckets=2)
    assert_same_weights(full, resumed)
    with pytest.raises(MotionlangError, match="length_buckets"):
        Trainer(TinyReg(), make_data(), collate, config(tmp_path, 1, length_buckets=-1))


def test_mid_epoch_resume_with_length_buckets(tmp_path):
    full, _, _ = run(tmp_path / "full", 3, checkpoint_every=2, length_buckets=2)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path / "cut", 3, checkpoint_every=2, fail_after=8, length_buckets=2)
    resumed, _, _ = run(tmp_path / "cut", 3, resume=True, init_seed=5, checkpoint_every=2,
                        length_buckets=2)
    assert_same_weights(full, resumed)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path / "cut2", 3, checkpoint_every=2, fail_after=8, length_buckets=2)
    with pytest.raises(MotionlangError, match="length_buckets"):   # another batch list
        run(tmp_path / "cut2", 3, resume=True, checkpoint_every=2, length_buckets=3)


@dataclasses.dataclass
class ScaleConfig:
    scale: float = 1.0


class ScaledReg(TinyReg):
    """TinyReg whose loss is multiplied by ``config.scale`` (a loss-changing option)."""

    def __init__(self, scale: float):
        super().__init__()
        self.config = ScaleConfig(scale)

    def to_checkpoint(self) -> dict:
        return {"kind": "scaled", "config": dataclasses.asdict(self.config),
                "state_dict": self.state_dict()}

    def loss(self, batch):
        return {k: v * self.config.scale for k, v in super().loss(batch).items()}


def test_resume_with_another_loss_ranks_best_afresh(tmp_path, caplog):
    def fit(epochs, scale, resume):
        torch.manual_seed(0)
        t = Trainer(ScaledReg(scale), make_data(), collate, config(tmp_path, epochs),
                    val_set=make_data(12, 1))
        return t.fit(resume=resume)

    fit(1, 1.0, False)
    fit(2, 1.0, True)        # same config: best still compares with epoch 1
    assert torch.load(tmp_path / "best.pt", weights_only=True)["best"] == \
        min(h["val"]["loss"] for h in json.loads((tmp_path / "history.json").read_text()))
    with caplog.at_level("WARNING"):
        hist = fit(3, 100.0, True)   # a 100x larger loss would never beat the old best
    assert "config differs" in caplog.text
    best = torch.load(tmp_path / "best.pt", weights_only=True)
    assert best["epoch"] == 3 and best["best"] == hist[-1]["val"]["loss"]


def test_learning_rate_by_hand():
    from motionlang.training.schedule import learning_rate
    # 8 steps, the last 4 decaying to 0: 1 + cos(pi/4), cos(pi/2), cos(3pi/4), cos(pi)
    got = [learning_rate(2.0, s, 8, 4, 0.0) for s in range(8)]
    r = 0.5 ** 0.5
    assert got == pytest.approx([2, 2, 2, 2, 1 + r, 1.0, 1 - r, 0.0])
    assert learning_rate(2.0, 7, 8, 4, 0.1) == pytest.approx(0.2)
    assert [learning_rate(2.0, s, 8, 1, 0.1) for s in range(8)] == pytest.approx([2.0] * 7 + [0.2])
    assert [learning_rate(2.0, s, 8, 0, 0.0) for s in range(8)] == [2.0] * 8


def test_decay_added_on_resume_equals_a_decayed_run(tmp_path):
    """A run trained at a constant rate, resumed with a decay over its new last epochs, is
    the same run as one planned with that decay from the start."""
    full, trainer, hist_full = run(tmp_path / "full", 4, decay_epochs=2, decay_to=0.1)
    assert [h["lr"] for h in hist_full[:2]] == [5e-3, 5e-3]
    assert hist_full[-1]["lr"] == pytest.approx(5e-4)
    assert trainer.optimizer.param_groups[0]["lr"] == pytest.approx(5e-4)
    assert 5e-4 < hist_full[2]["lr"] < 5e-3
    run(tmp_path / "part", 2)
    resumed, _, hist_res = run(tmp_path / "part", 4, resume=True, init_seed=7,
                               decay_epochs=2, decay_to=0.1)
    assert_same_weights(full, resumed)
    assert [h["lr"] for h in hist_full] == [h["lr"] for h in hist_res]
    plain, _, _ = run(tmp_path / "plain", 4)
    assert not all(torch.equal(a, b) for a, b in zip(full.state_dict().values(),
                                                    plain.state_dict().values()))


def test_mid_epoch_resume_inside_the_decay(tmp_path):
    full, _, hist_full = run(tmp_path / "full", 3, checkpoint_every=2, decay_epochs=1.5)
    with pytest.raises(KeyboardInterrupt):          # dies in epoch 3 (5 batches/epoch)
        run(tmp_path / "cut", 3, checkpoint_every=2, fail_after=12, decay_epochs=1.5)
    resumed, _, hist_res = run(tmp_path / "cut", 3, resume=True, init_seed=5,
                               checkpoint_every=2, decay_epochs=1.5)
    assert_same_weights(full, resumed)
    assert [h["lr"] for h in hist_full] == [h["lr"] for h in hist_res]
    assert hist_full[1]["lr"] < 5e-3                # the decay began inside epoch 2


def test_mid_epoch_resume_with_another_training_set_is_refused(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path / "cut", 3, checkpoint_every=2, fail_after=8)
    torch.manual_seed(0)
    trainer = Trainer(TinyReg(), make_data(80), collate, config(tmp_path / "cut", 3,
                                                                checkpoint_every=2))
    with pytest.raises(MotionlangError, match="training set size"):
        trainer.fit(resume=True)


def test_resume_into_another_model_size_is_a_clear_error(tmp_path):
    run(tmp_path / "part", 1)
    trainer = Trainer(torch.nn.Linear(4, 1), make_data(), collate, config(tmp_path / "part", 2))
    with pytest.raises(MotionlangError, match="does not fit"):
        trainer.fit(resume=True)


def test_resume_takes_the_new_learning_rate(tmp_path):
    run(tmp_path / "part", 1)
    _, trainer, hist = run(tmp_path / "part", 2, resume=True, lr=1e-3)
    assert hist[-1]["lr"] == 1e-3 and trainer.optimizer.param_groups[0]["lr"] == 1e-3


@pytest.mark.parametrize("kw", [{"decay_epochs": 5}, {"decay_epochs": -1}, {"decay_to": 1.5}])
def test_bad_decay_is_refused(tmp_path, kw):
    with pytest.raises(MotionlangError, match="decay"):
        run(tmp_path, 4, **kw)


def test_select_score_picks_best_pt_instead_of_the_validation_loss(tmp_path):
    """A ``select`` score that is best at epoch 2 of 4 (whatever the loss does) keeps epoch
    2's weights in best.pt and is recorded in the history."""
    scores = iter([0.5, 0.1, 0.3, 0.4])
    kept = {}

    def select(model):
        s = next(scores)
        kept[s] = {k: v.clone() for k, v in model.state_dict().items()}
        return s

    torch.manual_seed(0)
    model = TinyReg()
    hist = Trainer(model, make_data(), collate, config(tmp_path, 4), val_set=make_data(12, 1),
                   select=select).fit()
    assert [h["val"]["select"] for h in hist] == [0.5, 0.1, 0.3, 0.4]
    best = torch.load(tmp_path / "best.pt", weights_only=True)
    assert best["epoch"] == 2 and best["best"] == 0.1
    for k, v in best["model"]["state_dict"].items():
        assert torch.equal(v, kept[0.1][k]), k


def test_select_may_record_measures_beside_its_score(tmp_path):
    """A dict from ``select``: its "select" ranks best.pt, every number is recorded."""
    scores = iter([(0.2, 3.0), (0.6, 1.0)])

    def select(model):
        top3, fid = next(scores)
        return {"select": -top3, "top3": top3, "FID": fid}

    torch.manual_seed(0)
    hist = Trainer(TinyReg(), make_data(), collate, config(tmp_path, 2),
                   val_set=make_data(12, 1), select=select).fit()
    assert [(h["val"]["top3"], h["val"]["FID"]) for h in hist] == [(0.2, 3.0), (0.6, 1.0)]
    assert torch.load(tmp_path / "best.pt", weights_only=True)["epoch"] == 2
    with pytest.raises(MotionlangError, match="no 'select' score"):
        Trainer(TinyReg(), make_data(), collate, config(tmp_path / "b", 1),
                val_set=make_data(12, 1), select=lambda m: {"top3": 1.0}).fit()


def test_resume_that_starts_selecting_ranks_best_afresh(tmp_path, caplog):
    """best.pt ranked by the loss, resumed with a score of another scale (or the other way):
    the old best is not compared with the new scores."""
    def fit(epochs, select, resume):
        torch.manual_seed(0)
        return Trainer(TinyReg(), make_data(), collate, config(tmp_path, epochs),
                       val_set=make_data(12, 1), select=select).fit(resume=resume)

    fit(1, lambda m: -1e9, False)           # a score no loss could beat
    assert torch.load(tmp_path / "last.pt", weights_only=True)["best_by"] == "select"
    with caplog.at_level("WARNING"):
        hist = fit(2, None, True)
    assert "ranked best.pt by select, this run by loss" in caplog.text
    best = torch.load(tmp_path / "best.pt", weights_only=True)
    assert best["epoch"] == 2 and best["best"] == hist[-1]["val"]["loss"]


def test_a_resume_without_its_best_pt_ranks_afresh(tmp_path, caplog):
    scores = iter([0.1, 0.5])                 # the second epoch is worse than the first

    def fit(epochs, resume):
        torch.manual_seed(0)
        return Trainer(TinyReg(), make_data(), collate, config(tmp_path, epochs),
                       val_set=make_data(12, 1), select=lambda m: next(scores)
                       ).fit(resume=resume)

    fit(1, False)
    (tmp_path / "best.pt").unlink()           # e.g. a saved state that left it out
    with caplog.at_level("WARNING"):
        fit(2, True)
    assert "best.pt is missing" in caplog.text
    assert torch.load(tmp_path / "best.pt", weights_only=True)["epoch"] == 2


def test_what_ranked_an_older_checkpoint():
    from motionlang.training.run_files import ranked_by
    assert ranked_by({"best_by": "top-3 of x"}) == "top-3 of x"
    # written before best_by was recorded: its history says whether a select score ranked it
    assert ranked_by({"history": [{"val": {"loss": 1.0, "select": -0.5}}]}) == "select"
    assert ranked_by({"history": [{"val": {"loss": 1.0}}, {"val": None}]}) == "loss"


def test_weight_decay_leaves_a_part_frozen_after_an_earlier_stage_alone(tmp_path):
    torch.manual_seed(0)
    model = TinyReg()
    first = Trainer(model, make_data(), collate, config(tmp_path / "a", 1))
    first.fit()
    assert model.net[0].weight.grad is not None          # the first stage left gradients
    for p in model.net[0].parameters():                   # the second stage freezes layer 0
        p.requires_grad_(False)
    frozen = [p.detach().clone() for p in model.net[0].parameters()]
    second = Trainer(model, make_data(), collate,
                     config(tmp_path / "b", 2, optimizer="adamw", weight_decay=0.5))
    second.fit()
    assert all(torch.equal(a, b) for a, b in zip(frozen, model.net[0].parameters()))
    assert model.net[0].weight.grad is None

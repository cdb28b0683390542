"""Bad command-line input: one line, exit code 2, nothing written; bad configs, checkpoints
and non-finite training stopped where they arise (see benchmarks/cli_bad_inputs.py for the
table over every subcommand)."""
from __future__ import annotations

import math

import pytest

from motionlang.cli.main import main
from motionlang.errors import MotionlangError


def one_line_error(capsys, *fragments: str) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in lines[0], lines[0]
    return lines[0]


@pytest.mark.parametrize("argv, option", [
    (["render", "m.bvh", "o.gif", "--start", "nan"], "--start"),
    (["render", "m.bvh", "o.gif", "--end", "inf"], "--end"),
    (["render", "m.bvh", "o.gif", "--fps", "inf"], "--fps"),
    (["describe", "m.bvh", "-w", "0"], "-w/--width"),
    (["describe", "m.bvh", "-w", "1000000"], "-w/--width"),
    (["generate", "walk", "-o", "g.npz", "--seed", "-1"], "--seed"),
    (["generate", "walk", "-o", "g.npz", "--seed", str(2**70)], "--seed"),
    (["generate", "walk", "-o", "g.npz", "--max-frames", "-5"], "--max-frames"),
    (["generate", "walk", "-o", "g.npz", "--temperature", "inf"], "--temperature"),
    (["train", "m2l", "--data", "d", "--batch-size", "-1"], "--batch-size"),
    (["train", "m2l", "--data", "d", "--lr", "nan"], "--lr"),
    (["train", "m2l", "--data", "d", "--enc-hidden", "0"], "--enc-hidden"),
    (["train", "m2l", "--data", "d", "--dropout", "2"], "--dropout"),
    (["train", "l2m", "--data", "d", "--components", "0"], "--components"),
    (["train", "twostream", "--data", "d", "--out", "run", "--h", "0"], "--h"),
    (["train", "crbm", "--data", "d", "--out", "run", "--order", "1000000"], "--order"),
    (["train", "crbm", "--data", "d", "--out", "run", "--lr", "nan"], "--lr"),
    (["data", "split", "--data", "d", "--out", "s", "--fractions", "nan", "0.1", "0.1"],
     "--fractions"),
])
def test_bad_numbers_are_one_line(argv, option, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    line = one_line_error(capsys)
    # argparse's own check ("argument --x: ...") or the config's ("--x must be ...")
    assert f"argument {option}:" in line or f" {option.split('/')[-1]} must be" in line, line
    assert list(tmp_path.iterdir()) == []


def test_bad_output_paths(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x")
    before = sorted(tmp_path.rglob("*"))
    for argv, fragment in (
            (["render", "m.bvh", "adir"], "is a folder"),
            (["convert", "m.bvh", "afile/x.bvh"], "is not a folder"),
            (["generate", "walk", "-o", "/sys/x.gif"], "under /sys"),
            (["data", "synth", "--out", ""], "empty path"),
            (["data", "synth", "--out", "afile"], "is a file"),
            (["train", "m2l", "--data", "d", "--out", "afile/run"], "is not a folder"),
            (["demo", "--out", "/sys/demo"], "under /sys")):
        assert main(argv) == 2, argv
        one_line_error(capsys, fragment)
    assert sorted(tmp_path.rglob("*")) == before


def test_output_path_helpers_accept_good_paths(tmp_path):
    from motionlang.cli.options import output_dir, output_file
    assert output_file(str(tmp_path / "new" / "deeper" / "a.gif"))
    assert output_dir(str(tmp_path)) and output_dir(str(tmp_path / "new" / "run"))
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("content", [b"not a checkpoint\n", b"PK\x03\x04" + b"\0" * 100])
def test_unreadable_checkpoint_is_one_clear_line(content, tmp_path):
    from motionlang.models.checkpoint import read_model_dict
    path = tmp_path / "x.pt"
    path.write_bytes(content)
    with pytest.raises(MotionlangError) as info:
        read_model_dict(path, "m2l")
    msg = str(info.value)
    assert "\n" not in msg and "weights_only" not in msg and "not a readable" in msg


def test_describe_with_a_file_that_is_not_a_checkpoint(tmp_path, capsys):
    (tmp_path / "junk.pt").write_text("hello")
    assert main(["describe", str(tmp_path / "m.bvh"), "--model", str(tmp_path / "junk.pt")]) == 2
    line = one_line_error(capsys)
    assert "weights_only" not in line


@pytest.mark.parametrize("text", ["", "   ", "!!!"])
def test_text_without_words_is_an_error(text):
    from motionlang.models.t2m import generate_any
    with pytest.raises(MotionlangError, match="no words"):
        generate_any(None, text)


def test_resume_needs_a_readable_checkpoint(tmp_path):
    from motionlang.training.run_files import check_resume
    with pytest.raises(MotionlangError, match="no checkpoint"):
        check_resume(tmp_path)
    (tmp_path / "last.pt").write_bytes(b"PK\x03\x04")
    with pytest.raises(MotionlangError, match="not a readable"):
        check_resume(tmp_path)


def test_train_resume_without_checkpoint_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", "m2l", "--data", str(tmp_path), "--out", str(out), "--resume"]) == 2
    one_line_error(capsys, "--resume: no checkpoint")
    assert not out.exists()


def test_non_finite_loss_stops_training_keeping_the_last_good_checkpoint(tmp_path):
    import torch

    from helpers.trainer_tiny import TinyReg, collate, make_data
    from motionlang.training.trainer import TrainConfig, Trainer

    class GoesNaN(TinyReg):
        def loss(self, batch):
            out = super().loss(batch)   # counts its training calls
            if self.calls > 5:   # epoch 1 has 5 batches of 8
                out["loss"] = out["loss"] * float("nan")
            return out

    torch.manual_seed(0)
    cfg = TrainConfig(epochs=3, batch_size=8, lr=1e-2, seed=0, out_dir=str(tmp_path),
                      plot=False, progress=False)
    trainer = Trainer(GoesNaN(), make_data(40), collate, cfg)
    with pytest.raises(MotionlangError, match="step 6: loss term loss not finite"):
        trainer.fit()
    ck = torch.load(tmp_path / "last.pt", weights_only=True)
    assert ck["step"] == 5
    assert all(torch.isfinite(v).all() for v in ck["model"]["state_dict"].values())


def test_configs_check_their_numbers():
    from motionlang.models.crbm.config import CRBMConfig
    from motionlang.models.seq2seq.config import L2MConfig, M2LConfig
    from motionlang.models.twostream.config import TwoStreamConfig
    for make, match in ((lambda: M2LConfig(4, 9, dropout=2.0), "M2LConfig.dropout"),
                        (lambda: M2LConfig(4, 9, enc_hidden=0), "M2LConfig.enc_hidden"),
                        (lambda: L2MConfig(9, 4, n_components=0), "L2MConfig.n_components"),
                        (lambda: L2MConfig(9, 4, end_weight=math.nan), "L2MConfig.end_weight"),
                        (lambda: CRBMConfig(lr=math.nan), "CRBMConfig.lr"),
                        (lambda: CRBMConfig(order=0), "CRBMConfig.order"),
                        (lambda: TwoStreamConfig(h=0), "TwoStreamConfig.h")):
        with pytest.raises(MotionlangError, match=match):
            make()


def test_relative_bleu_is_undefined_for_a_vanishing_reference():
    from motionlang.evaluation.seq2seq import relative_bleu
    assert math.isnan(relative_bleu(2.4e-154, 1e-309))
    assert math.isnan(relative_bleu(0.945e-154, 1e-154))
    assert relative_bleu(0.2, 0.4) == pytest.approx(0.5)
    assert relative_bleu(1e-154, 0.4) == 0.0


def test_diverging_crbm_stops_with_its_epoch_named():
    import numpy as np

    from motionlang.models.crbm.config import CRBMConfig
    from motionlang.models.crbm.model import CRBM
    rng = np.random.default_rng(0)
    seqs = [rng.standard_normal((30, 3)) for _ in range(2)]
    model = CRBM(CRBMConfig(n_hidden=4, order=1, epochs=5, batch_size=10, lr=1e6,
                            lr_autoregressive=1e6), 3)
    with np.errstate(all="ignore"), pytest.raises(MotionlangError, match="stopped at epoch"):
        model.fit(seqs)

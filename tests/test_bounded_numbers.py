"""Numbers and long work (issue 44, items 4 and 5): absurd values refused with one line
before anything is allocated; deep rigs written without recursion; renders above a frame
limit refused until --max-frames allows them."""
from __future__ import annotations

import argparse
import os
from dataclasses import dataclass

import numpy as np
import pytest
import torch

from motionlang.cli.main import main
from motionlang.cli.options import float_range, positive_float, rate_float
from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.formats import read_motion, write_motion
from motionlang.rendering.scene import RENDER_MAX_FRAMES, sample_times
from motionlang.utils.checks import check_numbers


def _bvh(path, frame_time="0.01", joints=1, frames=3):
    lines = ["HIERARCHY", "ROOT j0", "{", " OFFSET 0 0 0",
             " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for i in range(1, joints):
        lines += [f"JOINT j{i}", "{", " OFFSET 0 0.01 0", " CHANNELS 3 Zrotation Xrotation "
                  "Yrotation"]
    lines += ["End Site", "{", " OFFSET 0 0.01 0", "}"] + ["}"] * joints
    row = " ".join(["0"] * (6 + 3 * (joints - 1)))
    lines += ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time}"] + [row] * frames
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("text", ["1e308", "1e-300", "nan", "inf", "-1e13"])
def test_option_numbers_beyond_any_use_are_refused(text):
    with pytest.raises(argparse.ArgumentTypeError, match="must be a finite number"):
        float_range()(text)
    assert positive_float("2.5e-4") == 2.5e-4 and float_range()("0") == 0.0
    with pytest.raises(argparse.ArgumentTypeError, match=r">= 0.01 and <= 10000"):
        rate_float(text)


def test_config_numbers_beyond_any_use_are_refused():
    @dataclass
    class Cfg:
        lr: float = 1e308

    with pytest.raises(MotionlangError, match=r"Cfg.lr must be a finite number > 0"):
        check_numbers("Cfg", Cfg(), positive=("lr",))
    with pytest.raises(MotionlangError, match=r"Cfg.lr must be a finite number >= 0"):
        check_numbers("Cfg", Cfg(1e-300), nonneg=("lr",))
    check_numbers("Cfg", Cfg(3e-4), positive=("lr",))


def test_a_frame_time_of_a_day_is_refused_before_resampling(tmp_path):
    m = read_motion(_bvh(tmp_path / "slow.bvh", frame_time="1e9"))
    with pytest.raises(MotionFormatError, match="re-timing 2e\\+09 s to 10 Hz: frame count"):
        m.resample(10.0)
    assert m.resample(1e-9).n_frames == 3
    m = read_motion(_bvh(tmp_path / "slow.bvh", frame_time="1e5", joints=300))
    with pytest.raises(MotionFormatError, match="memory needed for 2,000,001 frames"):
        m.resample(10.0)


def test_a_render_above_the_frame_limit_asks_for_max_frames(tmp_path, capsys):
    n = RENDER_MAX_FRAMES * 2
    with pytest.raises(MotionlangError, match="pass --max-frames"):
        sample_times(n, 25.0, 25.0)
    assert len(sample_times(n, 25.0, 25.0, max_frames=n)) == n
    slow = _bvh(tmp_path / "slow.bvh", frame_time="1e5")
    out = tmp_path / "o.gif"
    assert main(["render", str(slow), str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--max-frames" in err[0] and not out.exists()


def test_a_chain_of_1990_joints_converts_without_recursion(tmp_path):
    deep = read_motion(_bvh(tmp_path / "deep.bvh", joints=1990, frames=2))
    write_motion(deep, tmp_path / "again.bvh")
    back = read_motion(tmp_path / "again.bvh")
    assert len(back.skeleton.joints) == len(deep.skeleton.joints)
    assert np.allclose(back.joint_angles, deep.joint_angles)


def test_synth_refuses_absurd_counts_and_caps_its_workers(tmp_path, monkeypatch, capsys):
    from motionlang.datasets.synth import corpus
    assert main(["data", "synth", "--out", str(tmp_path / "a"), "--n", str(10**12)]) == 2
    assert "1..1,000,000 samples" in capsys.readouterr().err and not (tmp_path / "a").exists()
    seen = []

    class Pool:   # records the size asked for instead of forking
        def __init__(self, max_workers):
            seen.append(max_workers)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def map(self, fn, jobs, chunksize):
            return map(fn, jobs)

    monkeypatch.setattr(corpus, "ProcessPoolExecutor", Pool)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    ids = corpus.write_corpus(tmp_path / "b", 8, workers=10_000, show_progress=False)
    assert seen == [2] and len(ids) == 8


def test_pairs_refuse_an_empty_vocabulary_and_absurd_offsets(tmp_path):
    from motionlang.datasets.seq2seq_pairs import build_pairs
    from motionlang.datasets.synth.corpus import write_corpus
    write_corpus(tmp_path / "c", 3, workers=1, show_progress=False)
    with pytest.raises(MotionlangError, match="offsets.*1..100, got 1000000000"):
        build_pairs(tmp_path / "c", offsets=10**9)
    with pytest.raises(MotionlangError, match="vocabulary would be empty.*--min-count"):
        build_pairs(tmp_path / "c", min_count=10**9, offsets=1)


def test_contradictory_generation_options_are_refused():
    from motionlang.api import generate_hypotheses
    from motionlang.models.seq2seq.config import L2MConfig
    with pytest.raises(MotionlangError, match="--min-frames 50 exceeds --max-frames 10"):
        generate_hypotheses("a person walks", "no-such-model", max_frames=10, min_frames=50)
    with pytest.raises(MotionlangError, match="plan_weight and plan_noise apply to a plan"):
        L2MConfig(10, 20, plan_weight=2.0)
    L2MConfig(10, 20, plan_parts=3, plan_weight=2.0, progress_input=True)


def test_describing_features_that_are_not_finite_is_an_error():
    from motionlang.models.seq2seq.config import M2LConfig
    from motionlang.models.seq2seq.decode.search import describe_features
    from motionlang.models.seq2seq.m2l import MotionToLanguage
    torch.manual_seed(0)
    model = MotionToLanguage(M2LConfig(n_features=4, vocab_size=8, enc_hidden=8, dec_hidden=8,
                                       embed_dim=8))
    x = np.zeros((5, 4))
    x[2, 1] = np.inf
    with pytest.raises(MotionlangError, match="1 values that are not finite"):
        describe_features(model, x)

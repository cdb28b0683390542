"""The Taylor 2006 fill-in protocol on the real CMU subject 35 data (skips without it)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from helpers.data import shared_file
from motionlang.evaluation.crbm.fill import (
    ERASED,
    GAP_START_PAIR,
    fill_error,
    frame_mask,
    hold_last_fill,
    load_cmu35,
    nearest_neighbour_fill,
    per_frame_dims,
    score_space,
    taylor59,
)
from motionlang.evaluation.crbm.reproduce import (
    ReproduceConfig,
    format_table,
    model_frames,
    reproduce,
)
from motionlang.models.crbm.config import CRBMConfig


@pytest.fixture(scope="module")
def data():
    return load_cmu35(shared_file("cmu35/cmu35WalkJog.mat").parent)


def test_dataset_shape(data):
    assert len(data.train) == 31 and sum(len(t) for t in data.train) == 2644
    assert len(data.test["35_29"]) == 125 and len(data.test["35_18"]) == 44
    rows = np.vstack([score_space(taylor59(c), data.scale, data.bias) for c in data.train])
    assert rows.shape == (2613, 118)
    # the jog trials are the short ones (faster cadence, same distance)
    jog = [len(t) for t, n in zip(data.train, data.train_names) if data.labels[n] == "jog"]
    walk = [len(t) for t, n in zip(data.train, data.train_names) if data.labels[n] == "walk"]
    assert len(jog) == 9 and max(jog) < min(walk)


@pytest.mark.parametrize("part,paper", [("leg", 11.68), ("upper body", 22.20)])
def test_nearest_neighbour_reproduces_the_paper(data, part, paper):
    rows = np.vstack([score_space(taylor59(c), data.scale, data.bias) for c in data.train])
    true = score_space(taylor59(data.test["35_29"]), data.scale, data.bias)
    assert true.shape == (124, 118)
    dims = ERASED[part]
    filled = nearest_neighbour_fill(rows, true[GAP_START_PAIR:], dims)
    known = np.setdiff1d(np.arange(118), dims)
    assert np.array_equal(filled[:, known], true[GAP_START_PAIR:, known])
    err = fill_error(true[GAP_START_PAIR:], filled, dims, slice(None))
    assert err == pytest.approx(paper, rel=0.01)


def test_hold_last_value_is_constant_over_the_gap(data):
    x = taylor59(data.test["35_29"])
    fd = per_frame_dims(ERASED["leg"])
    assert list(fd) == list(range(16, 23))
    known = frame_mask(len(x), 62, fd, 59)
    held = hold_last_fill(x, known)
    assert np.array_equal(held[62:, fd], np.broadcast_to(x[61, fd], (len(x) - 62, len(fd))))
    assert np.array_equal(held[known], x[known])


def test_model_frames_use_root_displacement(data):
    c = data.test["35_29"]
    mf = model_frames(c)
    # the step's length is the world step's, whatever the facing frame
    np.testing.assert_allclose(np.hypot(mf[1:, 0], mf[1:, 2]),
                               np.hypot(np.diff(c[:, 0]), np.diff(c[:, 2])), atol=1e-9)
    np.testing.assert_allclose(mf[:, 1], c[:, 1])
    assert mf[1:, 2].mean() > 3 * np.abs(mf[1:, 0]).mean()   # a walk goes mostly forward


def test_reproduce_runs_and_is_deterministic(data):
    cfg = ReproduceConfig(crbm=CRBMConfig(n_hidden=16, epochs=3), n_repeats=4, n_gibbs=3, seed=5)
    r1 = reproduce(data_dir=shared_file("cmu35/cmu35WalkJog.mat").parent, cfg=cfg)
    r2 = reproduce(data_dir=shared_file("cmu35/cmu35WalkJog.mat").parent, cfg=cfg)
    assert json.dumps(r1, sort_keys=True) == json.dumps(r2, sort_keys=True)
    walk = r1["table"]["35_29"]
    assert walk["leg"]["nearest neighbour"] == pytest.approx(11.68, rel=0.01)
    assert walk["leg"]["erased frames"] == 63
    assert r1["table"]["35_18"]["leg"]["erased frames"] == 44 - 43 // 2
    text = format_table(r1)
    assert "walking (35_29)" in text and "jogging (35_18)" in text and "8.78" in text


def test_model_frames_unwrap_joint_angles_and_fold_back_to_the_protocol(data):
    """The model sees a jogging knee bend past 90 degrees as it is (the protocol's
    asin(sin(x)) folds 110 into 70); folding the model frames gives the protocol's values."""
    from motionlang.evaluation.crbm.fill import JOINT_CHANNELS
    from motionlang.evaluation.crbm.reproduce import to_protocol59, unwrap_degrees
    jog = data.train[data.train_names.index("35_20")]
    mf, t59 = model_frames(jog), taylor59(jog)
    np.testing.assert_allclose(to_protocol59(mf)[:, 9:], t59[:, 9:], atol=1e-9)
    knee = list(JOINT_CHANNELS).index(16) + 9          # rtibia rx in the 59-layout
    assert mf[:, knee].max() > 100 and t59[:, knee].max() <= 90
    # unwrapped: continuous where the folded channel has a kink (no 40-degree jump per frame)
    assert np.abs(np.diff(mf[:, knee])).max() < 40
    a = np.array([[170.0], [-175.0], [-160.0], [185.0 + 360.0]])
    np.testing.assert_allclose(unwrap_degrees(a)[:, 0], [170.0, 185.0, 200.0, 185.0 + 360.0 - 360.0])

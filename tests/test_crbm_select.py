"""Hyper-parameter selection on training trials only, and the forward-speed measure."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.evaluation.crbm_generation import FPS, METRES_PER_UNIT, forward_speed
from motionlang.models.crbm import CRBM, CRBMConfig


@pytest.mark.parametrize("ry_deg", [0.0, 30.0, -120.0])
def test_forward_speed_projects_the_step_on_the_facing_direction(ry_deg):
    T, ry = 20, np.deg2rad(ry_deg)
    f = np.zeros((T, 59))
    f[:, 4], f[:, 7] = np.sin(ry), np.cos(ry)        # sin / cos of the root's y rotation
    fwd = np.array([np.sin(ry), np.cos(ry)])          # facing direction in the (x, z) plane
    side = np.array([np.cos(ry), -np.sin(ry)])
    f[:, [0, 2]] = 0.7 * fwd
    assert forward_speed(f) == pytest.approx(0.7 * METRES_PER_UNIT * FPS)
    f[:, [0, 2]] = -0.7 * fwd                          # walking backwards counts negative
    assert forward_speed(f) == pytest.approx(-0.7 * METRES_PER_UNIT * FPS)
    f[:, [0, 2]] = 0.7 * side                          # side steps are not forward motion
    assert forward_speed(f) == pytest.approx(0.0, abs=1e-12)


def test_on_epoch_sees_every_snapshot_of_one_run():
    rng = np.random.default_rng(0)
    seqs = [rng.normal(size=(30, 3)) for _ in range(2)]
    seen = []

    def snap(epoch, model):
        seen.append((epoch, len(model.history), model.W.copy()))

    m = CRBM(CRBMConfig(n_hidden=4, order=2, epochs=5, batch_size=10), 3).fit(seqs, on_epoch=snap)
    assert [s[0] for s in seen] == [1, 2, 3, 4, 5] and [s[1] for s in seen] == [1, 2, 3, 4, 5]
    np.testing.assert_array_equal(seen[-1][2], m.W)
    assert not np.array_equal(seen[0][2], seen[-1][2])   # snapshots differ: training went on
    # the same run without the callback ends in the same place (the callback is passive)
    m2 = CRBM(CRBMConfig(n_hidden=4, order=2, epochs=5, batch_size=10), 3).fit(seqs)
    np.testing.assert_array_equal(m2.W, m.W)


def test_validation_split_holds_out_training_trials_only():
    from conftest import shared_file
    from motionlang.evaluation.crbm_fill import load_cmu35
    from motionlang.evaluation.crbm_select import VALIDATION_TRIALS, validation_split
    data = load_cmu35(shared_file("cmu35/cmu35WalkJog.mat").parent)
    val = validation_split(data)
    assert len(val.train) == 27 and set(val.test) == set(VALIDATION_TRIALS)
    assert not set(val.train_names) & set(VALIDATION_TRIALS)
    assert not {"35_18", "35_29"} & set(val.test)          # the test trials are never used
    assert sorted(val.labels[t] for t in val.test) == ["jog", "jog", "walk", "walk"]
    for name in VALIDATION_TRIALS:
        np.testing.assert_array_equal(val.test[name], data.train[data.train_names.index(name)])

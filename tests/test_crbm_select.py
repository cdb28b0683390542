"""Hyper-parameter selection on training trials only, and the forward-speed measure."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.evaluation.crbm.generation import FPS, METRES_PER_UNIT, forward_speed
from motionlang.models.crbm.config import CRBMConfig
from motionlang.models.crbm.model import CRBM


@pytest.mark.parametrize("ry_deg", [0.0, 30.0, -120.0])
def test_forward_speed_is_the_step_along_the_facing_direction(ry_deg):
    from motionlang.evaluation.crbm.reproduce import body_to_world, model_frames, world_to_body
    T, ry = 20, np.deg2rad(ry_deg)
    fwd = np.array([np.sin(ry), np.cos(ry)])          # facing direction in the (x, z) plane
    side = np.array([np.cos(ry), -np.sin(ry)])
    s, c = np.full(T, np.sin(ry)), np.full(T, np.cos(ry))
    for world, want in ((0.7 * fwd, 0.7), (-0.7 * fwd, -0.7), (0.7 * side, 0.0)):
        body = world_to_body(np.tile(world, (T, 1)), s, c)
        f = np.zeros((T, 59))
        f[:, [0, 2]] = body
        assert forward_speed(f) == pytest.approx(want * METRES_PER_UNIT * FPS, abs=1e-12)
        # back to the world, also from a (sin, cos) pair that is not unit length
        np.testing.assert_allclose(body_to_world(body, 2 * s, 2 * c), np.tile(world, (T, 1)),
                                   atol=1e-12)
    # channels walking along the facing direction give that speed through model_frames
    ch = np.zeros((T, 62))
    ch[:, 4] = ry_deg
    ch[:, [0, 2]] = np.arange(T)[:, None] * 0.5 * fwd
    assert forward_speed(model_frames(ch)) == pytest.approx(0.5 * METRES_PER_UNIT * FPS)


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
    from experiments.lab.crbm_select import VALIDATION_TRIALS, validation_split

    from helpers.data import shared_file
    from motionlang.evaluation.crbm.fill import load_cmu35
    data = load_cmu35(shared_file("cmu35/cmu35WalkJog.mat").parent)
    val = validation_split(data)
    assert len(val.train) == 27 and set(val.test) == set(VALIDATION_TRIALS)
    assert not set(val.train_names) & set(VALIDATION_TRIALS)
    assert not {"35_18", "35_29"} & set(val.test)          # the test trials are never used
    assert sorted(val.labels[t] for t in val.test) == ["jog", "jog", "walk", "walk"]
    for name in VALIDATION_TRIALS:
        np.testing.assert_array_equal(val.test[name], data.train[data.train_names.index(name)])


def test_choose_prefers_the_best_eligible_run_and_falls_back_to_the_best():
    from experiments.lab.crbm_select import choose

    def run(score, kept):
        return {"score": score, "generation": {"a": {"style_kept": kept[0]},
                                               "b": {"style_kept": kept[1]}}}
    runs = [run(0.5, (1.0, 0.2)), run(0.6, (0.95, 0.9)), run(0.7, (1.0, 1.0))]
    best, ok = choose(runs, 0.9, held_out=("a", "b"))
    assert best is runs[1] and ok == runs[1:]          # 0.5 fails the gate on trial b
    best, ok = choose(runs, 0.99, held_out=("a", "b"))
    assert best is runs[2] and ok == [runs[2]]
    best, ok = choose(runs[:1], 0.9, held_out=("a", "b"))
    assert best is runs[0] and ok == []                 # nobody eligible: best overall

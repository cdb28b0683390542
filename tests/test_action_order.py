"""Nearest-primitive segment labels and the action-order check, on hand-made sequences."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.errors import MotionlangError
from motionlang.evaluation.action_order import (
    Prototypes,
    merge_repeats,
    order_accuracy,
    order_matches,
    rescale_ranges,
    segment_accuracy,
    segment_descriptor,
    segment_labels,
)


def still(T, level=0.0):
    return np.full((T, 3), level)


def wave(T, amp=1.0):
    t = np.arange(T)[:, None]
    return np.concatenate([amp * np.sin(t), np.zeros((T, 2))], axis=1)


def test_descriptor_hand_values():
    x = np.array([[0.0], [2.0], [1.0]])
    # mean 1, population std sqrt(2/3), mean |diff| (2 + 1) / 2
    np.testing.assert_allclose(segment_descriptor(x), [1.0, np.sqrt(2 / 3), 1.5])
    np.testing.assert_allclose(segment_descriptor([[4.0]]), [4.0, 0.0, 0.0])
    with pytest.raises(MotionlangError):
        segment_descriptor(np.zeros((0, 3)))


def test_labels_and_order():
    rng = np.random.default_rng(0)
    train = [("stand", still(20) + rng.normal(0, 0.01, (20, 3))) for _ in range(3)]
    train += [("wave", wave(20) + rng.normal(0, 0.01, (20, 3))) for _ in range(3)]
    train += [("squat", still(20, -1.0) + rng.normal(0, 0.01, (20, 3))) for _ in range(3)]
    protos = Prototypes.fit(train)
    assert protos.labels == ["squat", "stand", "wave"]
    seq = np.concatenate([still(15), wave(25, 0.9), still(10, -1.0)])
    ranges = [(0, 15), (15, 40), (40, 50)]
    assert segment_labels(seq, ranges, protos) == ["stand", "wave", "squat"]
    truth = ["stand", "wave", "squat"]
    swapped = np.concatenate([still(15), still(25, -1.0), wave(10)])
    labels = segment_labels(swapped, ranges, protos)
    assert labels == ["stand", "squat", "wave"]
    assert order_matches(segment_labels(seq, ranges, protos), truth)
    assert not order_matches(labels, truth)
    assert order_accuracy([truth, labels], [truth, truth]) == 0.5


def test_merge_and_rescale():
    assert merge_repeats(["walk", "walk", "turn", "walk"]) == ["walk", "turn", "walk"]
    assert order_matches(["walk", "walk", "turn"], ["walk", "turn", "turn"])
    # 100 Hz ranges of a 400-frame motion -> a 50-frame generated motion (12.5 Hz)
    assert rescale_ranges([(0, 160), (160, 400)], 400, 50) == [(0, 20), (20, 50)]
    # a range shorter than one output frame still gets one frame, inside the sequence
    assert rescale_ranges([(398, 400)], 400, 50) == [(49, 50)]
    with pytest.raises(MotionlangError):
        order_accuracy([], [])


def test_segment_accuracy_first_and_later():
    truth = [["walk", "turn", "walk"], ["jump", "wave"], ["stand"]]
    pred = [["walk", "stand", "walk"], ["stand", "wave"], ["stand"]]
    assert segment_accuracy(pred, truth) == (2 / 3, 2 / 3)   # later: turn x, walk ok, wave ok
    first, later = segment_accuracy([["stand"]], [["stand"]])
    assert first == 1.0 and np.isnan(later)
    with pytest.raises(MotionlangError):
        segment_accuracy([["walk"]], [["walk", "turn"]])


def test_nearest_example_mode():
    # two clusters of "wave" far apart (small and large) whose centroid lies far from a
    # small wave: the centroid labeller calls it "stand", 1-NN over the examples "wave"
    train = [("wave", wave(20, 0.2)), ("wave", wave(20, 3.0)),
             ("stand", still(20, 0.0)), ("stand", still(20, 0.05))]
    central = Prototypes.fit(train)
    nn = Prototypes.fit(train, nearest_example=True)
    assert central.examples is None and nn.examples.shape == (4, 9)
    assert sorted(nn.example_labels) == ["stand", "stand", "wave", "wave"]
    probe = wave(20, 0.2)
    assert central.label(probe) == "stand" and nn.label(probe) == "wave"
    assert nn.label(still(20, 0.02)) == "stand"
    # same centroids either way
    np.testing.assert_allclose(nn.centroids, central.centroids)


def test_segment_tally_by_hand():
    from motionlang.evaluation.action_order import segment_tally
    pred = [["walk", "stand", "wave"], ["kick", "stomp"]]
    truth = [["walk", "kick", "wave"], ["kick", "kick"]]
    right, confusions = segment_tally(pred, truth)
    assert right == {("first", "walk"): [1, 1], ("later", "kick"): [0, 2],
                     ("later", "wave"): [1, 1], ("first", "kick"): [1, 1]}
    assert confusions == {("kick", "stand"): 1, ("kick", "stomp"): 1}
    with pytest.raises(MotionlangError):
        segment_tally([["walk"]], [["walk", "kick"]])

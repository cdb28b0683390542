"""The sentence -> length regression that sets how long a two-stream generation runs."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from motionlang.errors import MotionlangError
from motionlang.models.length import SentenceLength
from motionlang.models.twostream.model import DEFAULT_SECONDS


def test_fit_recovers_additive_lengths():
    # lengths made of a base of 10 frames plus 20 per "walk" and 5 per "wave"; "a person"
    # appears everywhere, so the base is shared among "a", "person" and the bias (which
    # share, the minimum-norm solution decides). Without a penalty, exact
    sentences = ["a person walks", "a person waves", "a person walks walks",
                 "a person walks waves", "a person waves waves waves"]
    lengths = [30, 15, 50, 35, 25]
    m = SentenceLength.fit(sentences, lengths, ridge=0.0)
    assert m.frames("a person walks waves waves") == 40
    assert m.frames("A person walks.") == 30             # normalised like every sentence
    # clipped to the training range [15, 50]
    assert m.frames("walks walks walks walks") == 50
    assert m.frames("a person jumps") == 15              # unknown words count 0: 10 -> 15
    assert (m.low, m.high) == (15, 50)
    # a penalty shrinks the word weights, never the bias
    big = SentenceLength.fit(sentences, lengths, ridge=1e6)
    assert max(abs(w) for w in big.weights) < 0.1
    assert big.bias == pytest.approx(np.mean(lengths), abs=0.5)
    assert SentenceLength.from_dict(m.to_dict()) == m


def test_fit_checks_its_input():
    with pytest.raises(MotionlangError, match="as many lengths"):
        SentenceLength.fit(["a"], [1, 2])
    with pytest.raises(MotionlangError, match="at least one"):
        SentenceLength.fit([], [])


def test_model_carries_its_length_model(tmp_path):
    from helpers.twostream import HashTokens, tiny
    from motionlang.features.normalizer import Normalizer
    from motionlang.models.t2m import generate_any
    from motionlang.models.twostream.model import TwoStreamModel
    m = tiny()
    m.normalizer = Normalizer().fit(np.random.default_rng(0).normal(size=(50, 66)))
    default = round(DEFAULT_SECONDS * m.fps)
    assert m.frames_for("a person walks") == default == 125       # none fitted: 10 s
    m.length_model = SentenceLength.fit(["walks", "walks walks"], [8, 12], ridge=0.0)
    m.eval().save(tmp_path / "ts.pt")
    back = TwoStreamModel.load(tmp_path / "ts.pt", text_encoder=HashTokens())
    assert back.length_model == m.length_model and back.frames_for("walks walks") == 12
    (pos, _), = generate_any(back, "walks")
    assert pos.shape == (8, 21, 3)
    (pos, _), = generate_any(back, "walks", max_frames=5)        # a given length wins
    assert pos.shape == (5, 21, 3)
    # a checkpoint written before length models existed loads with none
    d = torch.load(tmp_path / "ts.pt", weights_only=True)
    del d["length_model"]
    old = TwoStreamModel.from_checkpoint(d, text_encoder=HashTokens())
    assert old.length_model is None and old.frames_for("walks") == default

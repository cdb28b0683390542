"""Collation and the describe / generate Python API on tiny trained models."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers.seq2seq import F_DIM, WORDS, items, tiny
from motionlang.errors import MotionlangError
from motionlang.models.seq2seq.decode.motion_beam import mean_decode
from motionlang.models.seq2seq.decode.search import (
    describe_features,
    encode_sentence,
    generate_features,
)
from motionlang.training.collate import collate_pairs
from motionlang.training.trainer import TrainConfig, Trainer

torch.set_num_threads(1)
def test_collate_pads_and_counts():
    batch = collate_pairs(items()[:3])
    assert batch["motion"].shape == (3, 8, F_DIM) and batch["motion"].dtype == torch.float32
    assert batch["motion_lengths"].tolist() == [6, 7, 8]
    assert batch["tokens"].tolist() == [[1, 4, 5, 6, 7, 2, 0], [1, 8, 7, 6, 5, 4, 2],
                                         [1, 4, 5, 6, 7, 2, 0]]
    assert batch["token_lengths"].tolist() == [6, 7, 6]
    assert float(batch["motion"][0, 6:].abs().sum()) == 0.0


def test_describe_after_training_with_the_trainer(tmp_path):
    data = items()
    model = tiny("m2l", False)
    allm = np.concatenate([d["motion"] for d in data])
    model.normalizer = {"mean": allm.mean(0), "std": allm.std(0)}
    norm = [{"motion": (d["motion"] - allm.mean(0)) / allm.std(0), "tokens": d["tokens"]}
            for d in data]
    Trainer(model, norm, collate_pairs, TrainConfig(epochs=60, batch_size=4, lr=1e-2,
                                                    out_dir=str(tmp_path), plot=False,
                                                    progress=False)).fit()
    model.save(tmp_path / "m2l.pt")
    model = type(model).load(tmp_path / "m2l.pt")
    for d in data[:2]:
        want = " ".join(WORDS[i] for i in d["tokens"][1:-1])
        hyps = describe_features(model, d["motion"], width=3)
        assert len(hyps) == 3 and hyps[0][0] == want
        assert hyps[0][1] > hyps[1][1] >= hyps[2][1]
        assert describe_features(model, d["motion"], width=1)[0][0] == want
    with pytest.raises(MotionlangError, match="shape"):
        describe_features(model, np.zeros((5, F_DIM + 1)))


def test_generate_returns_denormalised_frames():
    model = tiny("l2m", False)
    mean, std = np.arange(F_DIM, dtype=np.float32), np.full(F_DIM, 2.0, np.float32)
    model.normalizer = {"mean": mean, "std": std}
    ids = encode_sentence(WORDS, "w4 w5 never-seen")
    assert ids == [1, 4, 5, 3, 2]
    (frames, score), = generate_features(model, "w4 w5", method="mean", max_frames=6)
    raw = mean_decode(model.step, model.encode(torch.tensor([[1, 4, 5, 2]]), torch.tensor([4])),
                      batch_size=1, max_frames=6, dim=F_DIM)[0]
    np.testing.assert_allclose(frames, raw.frames * std + mean, rtol=1e-5)
    assert score == pytest.approx(raw.score)
    beams = generate_features(model, "w4 w5", width=3, max_frames=6, seed=1)
    assert 1 <= len(beams) <= 3 and all(f.shape[1] == F_DIM for f, _ in beams)
    again = generate_features(model, "w4 w5", width=3, max_frames=6, seed=1)
    np.testing.assert_array_equal(beams[0][0], again[0][0])        # seeded: reproducible

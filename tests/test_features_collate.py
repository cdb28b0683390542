import numpy as np
import pytest
import torch

from motionlang.features.collate import lengths_to_mask, pad_batch, unpad


def test_pad_batch_numpy_values_and_mask():
    seqs = [np.full((3, 2), 1.0), np.full((1, 2), 2.0), np.full((4, 2), 3.0)]
    batch, mask = pad_batch(seqs, value=-9.0)
    assert batch.shape == (3, 4, 2) and mask.shape == (3, 4) and mask.dtype == bool
    assert mask.sum(1).tolist() == [3, 1, 4]
    assert np.all(batch[0, 3] == -9.0) and np.all(batch[1, 1:] == -9.0)
    assert np.all(batch[2] == 3.0)
    back = unpad(batch, mask)
    assert all(np.array_equal(a, b) for a, b in zip(back, seqs))


def test_pad_batch_torch_and_fixed_length():
    seqs = [torch.arange(3), torch.arange(5)]
    batch, mask = pad_batch(seqs, length=6)
    assert isinstance(batch, torch.Tensor) and batch.shape == (2, 6)
    assert mask.tolist()[0] == [True] * 3 + [False] * 3
    assert batch[1, :5].tolist() == [0, 1, 2, 3, 4] and batch[1, 5] == 0
    with pytest.raises(ValueError, match="does not fit"):
        pad_batch(seqs, length=4)
    with pytest.raises(ValueError, match="trailing shapes"):
        pad_batch([np.zeros((2, 3)), np.zeros((2, 4))])


def test_lengths_to_mask():
    m = lengths_to_mask(np.array([0, 2]), max_len=3)
    assert m.tolist() == [[False, False, False], [True, True, False]]
    t = lengths_to_mask(torch.tensor([1, 3]))
    assert t.tolist() == [[True, False, False], [True, True, True]]

import json

import numpy as np
import pytest
import torch

from motionlang.errors import MotionlangError
from motionlang.features.normalizer import Normalizer


def _data(seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(loc=[1.0, -2.0, 5.0, 0.0], scale=[0.5, 3.0, 1e-3, 1.0], size=(500, 4))
    x[:, 3] = 7.0  # a constant dimension
    return x


def test_zscore_stats_and_inverse():
    x = _data()
    n = Normalizer().fit(x)
    z = n.transform(x)
    assert np.allclose(z[:, :3].mean(0), 0, atol=1e-9)
    assert np.allclose(z[:, :3].std(0), 1, atol=1e-9)
    # the constant dimension is centred, not divided by ~0
    assert np.all(z[:, 3] == 0) and n.std[3] == 1.0
    assert np.allclose(n.inverse(z), x, atol=1e-12)


def test_fit_on_list_of_sequences_equals_concatenation():
    x = _data()
    a = Normalizer().fit([x[:100], x[100:]])
    b = Normalizer().fit(x)
    assert np.allclose(a.mean, b.mean) and np.allclose(a.std, b.std)


def test_torch_tensors_keep_type_and_dtype():
    x = _data()
    n = Normalizer().fit(x)
    t = torch.tensor(x[:10], dtype=torch.float32)
    z = n.transform(t)
    assert isinstance(z, torch.Tensor) and z.dtype == torch.float32
    # float32 arithmetic: (5.0006 - 4.9999) / 1e-3 loses ~1e-3 in the tiny-std column
    assert np.allclose(z.numpy(), n.transform(x[:10]), atol=2e-3)
    assert n.transform(t.double()).dtype == torch.float64
    assert torch.allclose(n.inverse(z), t, atol=1e-4)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_save_load_round_trip(tmp_path, suffix):
    n = Normalizer(names=["a", "b", "c", "d"]).fit(_data())
    path = tmp_path / f"norm{suffix}"
    n.save(path)
    m = Normalizer.load(path)
    assert np.allclose(m.mean, n.mean, rtol=0, atol=0 if suffix == ".npz" else 1e-15)
    assert np.allclose(m.std, n.std) and m.names == ["a", "b", "c", "d"]
    # to_dict is plain JSON (embeddable in checkpoints)
    assert Normalizer.from_dict(json.loads(json.dumps(n.to_dict()))).dim == 4


def test_errors():
    with pytest.raises(MotionlangError, match="not fitted"):
        Normalizer().transform(np.zeros((2, 3)))
    n = Normalizer().fit(_data())
    with pytest.raises(MotionlangError, match="expects 4"):
        n.transform(np.zeros((2, 3)))
    with pytest.raises(MotionlangError, match="non-finite"):
        Normalizer().fit(np.array([[1.0, np.nan]]))
    with pytest.raises(MotionlangError, match="positive std"):
        Normalizer.from_dict({"mean": [0.0], "std": [0.0]})


def test_load_garbage_names_the_file(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(MotionlangError, match="bad.json"):
        Normalizer.load(bad)
    badz = tmp_path / "bad.npz"
    badz.write_bytes(b"not a zip")
    with pytest.raises(MotionlangError, match="bad.npz"):
        Normalizer.load(badz)

"""The .npz feature cache: hits, invalidation by source identity, corrupt files."""
from __future__ import annotations

import os

import numpy as np
import pytest

from motionlang.datasets.cache import cache_dir, cache_key, cached, file_identity


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_hit_miss_and_invalidation(tmp_path, cache):
    src = tmp_path / "m.txt"
    src.write_text("abc")
    calls = []

    def compute():
        calls.append(1)
        return {"x": np.arange(6, dtype=np.float32).reshape(2, 3) * len(calls), "n": 3}

    key = {"src": file_identity(src), "fps": 20}
    a = cached(key, compute, name="feat")
    b = cached(key, compute, name="feat")
    assert len(calls) == 1 and cache_dir() == cache
    assert b["x"].dtype == np.float32 and np.array_equal(a["x"], b["x"]) and int(b["n"]) == 3
    assert len(list(cache.glob("feat-*.npz"))) == 1
    cached({"src": file_identity(src), "fps": 30}, compute, name="feat")   # option changed
    assert len(calls) == 2
    src.write_text("abcd")                                                 # source changed
    os.utime(src, ns=(1, 1))
    c = cached({"src": file_identity(src), "fps": 20}, compute, name="feat")
    assert len(calls) == 3 and c["x"][0, 1] == 3
    cached(key, compute, name="feat", refresh=True)
    assert len(calls) == 4


def test_corrupt_file_is_recomputed(cache):
    calls = []

    def compute():
        calls.append(1)
        return {"y": np.ones(4)}

    cached({"k": 1}, compute)
    (path,) = cache.glob("*.npz")
    path.write_bytes(b"garbage, not an npz")
    out = cached({"k": 1}, compute)
    assert len(calls) == 2 and np.array_equal(out["y"], np.ones(4))
    assert cached({"k": 1}, compute)["y"].shape == (4,) and len(calls) == 2   # rewritten


def test_key_is_canonical():
    assert cache_key({"a": 1, "b": [1, 2]}) == cache_key({"b": [1, 2], "a": 1})
    assert cache_key({"a": 1}) != cache_key({"a": 2})

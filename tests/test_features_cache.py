"""dataset_features: fitted + encoded dataset through the on-disk cache (hit, misses)."""
import os
import shutil

import numpy as np
import pytest

from helpers.data import shared_file
from motionlang.datasets.custom import CustomRecord
from motionlang.datasets.feature_cache import dataset_features, record_sources
from motionlang.datasets.kitml import KitMLRecord
from motionlang.errors import MotionlangError
from motionlang.formats.bvh import write_bvh


class Counting:
    """Wraps a record, counting how often its motion is read."""

    def __init__(self, record, reads):
        self._r, self._reads = record, reads

    def __getattr__(self, name):
        return getattr(self._r, name)

    def load_motion(self):
        self._reads.append(self._r.id)
        return self._r.load_motion()


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_kitml_positions_hit_and_misses(tmp_path, cache):
    src = tmp_path / "00001_mmm.xml"
    shutil.copy(shared_file("kitml/00001_mmm.xml"), src)
    reads = []
    recs = [Counting(KitMLRecord("00001", src, ["a person walks"]), reads)]
    first = dataset_features(recs, "positions", {"fps": 12.5})
    assert len(reads) == 1  # read once: its rows fit the features and are encoded
    (x,) = first.sequences["00001"]
    assert x.shape == (len(np.arange(0, 378, 8)), first.features.dim)
    # the very numbers of fitting on the motion and encoding it, reading it twice
    from motionlang.features.positions import PositionFeatures
    motion = recs[0].load_motion()
    ref = PositionFeatures(fps=12.5).fit([motion])
    assert np.array_equal(ref.encode(motion), x)
    assert ref.to_dict() == first.features.to_dict()
    reads.clear()
    second = dataset_features(recs, "positions", {"fps": 12.5})
    assert len(reads) == 0  # a hit: no motion read again
    assert np.array_equal(second.sequences["00001"][0], x)
    assert second.features.to_dict() == first.features.to_dict()
    assert len(list(cache.glob("*.npz"))) == 2

    dataset_features(recs, "positions", {"fps": 25.0})  # an option changed
    assert len(reads) == 1
    st = src.stat()
    os.utime(src, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))  # the source touched
    dataset_features(recs, "positions", {"fps": 12.5})
    assert len(reads) == 2
    dataset_features(recs, "positions", {"fps": 12.5}, refresh=True)
    assert len(reads) == 3
    # mirrored: the fit is the unmirrored one's (a hit), each motion read to be mirrored
    dataset_features(recs, "positions", {"fps": 12.5}, mirror=True)
    assert len(reads) == 4


def test_angles_keep_every_offset(tmp_path, cache):
    rec = KitMLRecord("00001", shared_file("kitml/00001_mmm.xml"), [])
    out = dataset_features([rec], "angles", directory=tmp_path / "elsewhere")
    seqs = out.sequences["00001"]
    assert len(seqs) == 10 and seqs[0].shape[1] == out.features.dim  # offsets 0..9 at 10 Hz
    assert not cache.exists() and len(list((tmp_path / "elsewhere").glob("*.npz"))) == 2


def test_custom_bvh_taylor_and_bad_options(tmp_path, cache, tiny_motion):
    write_bvh(tiny_motion, tmp_path / "a.bvh")
    write_bvh(tiny_motion[:12], tmp_path / "b.bvh")
    recs = [CustomRecord("a", tmp_path / "a.bvh"), CustomRecord("b", tmp_path / "b.bvh")]
    reads = []
    wrapped = [Counting(r, reads) for r in recs]
    out = dataset_features(wrapped, "taylor", fit_records=wrapped[:1])
    assert reads == ["a", "a", "b"]  # fit on the first only
    assert [len(out.sequences[k][0]) for k in "ab"] == [20, 12]
    assert dataset_features(wrapped, "taylor", fit_records=wrapped[:1]).sequences.keys() == \
        out.sequences.keys() and len(reads) == 3
    dataset_features(wrapped, "taylor")  # other fit records: both stages miss
    assert len(reads) == 3 + 2 + 2
    assert record_sources(recs[0]) == [tmp_path / "a.bvh"]
    with pytest.raises(MotionlangError, match="unknown feature kind"):
        dataset_features(recs, "nope")
    with pytest.raises(MotionlangError, match="taylor features"):
        dataset_features(recs, "taylor", {"no_such_option": 1})
    with pytest.raises(MotionlangError, match="not unique"):
        dataset_features(recs + recs[:1], "taylor")

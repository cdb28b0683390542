"""CMU subject 35 walk/jog and MIT walking as named datasets."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.datasets.named import (
    CMU35_TEST_TRIALS,
    CMU35_TRAIN_TRIALS,
    cmu35_walkjog,
    default_data_dir,
    mit_walk,
)
from motionlang.errors import DatasetError


@pytest.fixture(scope="module")
def cmu(shared_data):
    return cmu35_walkjog(shared_data)


def _speed(motion) -> float:
    """Mean horizontal root speed, m/s (canonical frame, Y up)."""
    p = motion.positions()[:, 0, [0, 2]]
    return float(np.linalg.norm(p[-1] - p[0]) / (motion.n_frames - 1) * motion.fps)


def test_cmu35_trials_and_arrays(cmu):
    assert [t.trial for t in cmu.train] == list(CMU35_TRAIN_TRIALS) and len(cmu.train) == 31
    assert [t.trial for t in cmu.test] == list(CMU35_TEST_TRIALS)
    assert cmu.Y.shape == (2644, 62) and cmu.lbls.shape == (2644, 31)
    assert cmu.Ytest.shape == (169, 62) and cmu.lblstest.shape == (169, 2)
    assert sum(t.motion.n_frames for t in cmu.train) == 2644
    t18, t29 = cmu.test
    assert (t18.label, t18.rows, t29.label, t29.rows) == ("jog", (0, 44), "walk", (44, 169))
    assert all(t.motion.fps == 30.0 for t in cmu.trials)
    # the motions reproduce the raw channels they were built from
    from motionlang.formats.asf_amc import motion_to_channels
    t = cmu.train[5]
    np.testing.assert_allclose(motion_to_channels(t.motion), cmu.Y[t.rows[0]:t.rows[1]],
                               atol=1e-6)


def test_cmu35_labels_match_the_motion(cmu):
    """Jogs cover the capture volume in under half the frames of any walk, and faster."""
    jog = [t for t in cmu.trials if t.label == "jog"]
    walk = [t for t in cmu.trials if t.label == "walk"]
    assert len(jog) == 10 and len(walk) == 23
    assert max(t.motion.n_frames for t in jog) * 2 < min(t.motion.n_frames for t in walk)
    assert min(_speed(t.motion) for t in jog) > 1.5 * max(_speed(t.motion) for t in walk)
    for t in walk:      # a plausible walking speed, feet on the ground
        assert 0.5 < _speed(t.motion) < 2.5
        assert abs(t.motion.positions()[:, :, 1].min()) < 0.1


def test_default_data_dir(monkeypatch, tmp_path, shared_data):
    monkeypatch.setenv("MOTIONLANG_DATA", str(shared_data))
    assert default_data_dir() == shared_data
    monkeypatch.setenv("MOTIONLANG_DATA", str(tmp_path / "nope"))
    with pytest.raises(DatasetError, match="MOTIONLANG_DATA"):
        default_data_dir()
    with pytest.raises(DatasetError, match="cmu35WalkJog.mat: missing"):
        cmu35_walkjog(tmp_path)


def test_mit_walk(shared_data):
    pytest.importorskip("motionlang.formats.mit")
    seqs = mit_walk(shared_data)
    assert [m.n_frames for m in seqs] == [438, 260, 3128]
    assert all(m.fps == 30.0 for m in seqs)


def test_cmu_dev_is_extracted_once_outside_the_data(shared_data, tmp_path):
    from motionlang.datasets.named import cmu_dev_folder
    if not (shared_data / "cmu_dev" / "cmu-dev.tar.xz").is_file():
        pytest.skip("no cmu_dev archive")
    folder = cmu_dev_folder(shared_data, tmp_path)
    assert folder == tmp_path / "cmu-dev"
    assert len(list(folder.glob("*/*.bvh"))) == 59
    stamp = (folder / "iclone").stat().st_mtime_ns
    assert cmu_dev_folder(shared_data, tmp_path) == folder     # not extracted again
    assert (folder / "iclone").stat().st_mtime_ns == stamp

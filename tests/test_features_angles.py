import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import synthetic_mmm, turn
from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features import AnglesFeatures, FeatureSet, features_from_dict, pad_batch
from motionlang.features.root import root_trajectory
from motionlang.formats.mmm import read_mmm
from motionlang.formats.mmm_model import MMM_DOF_ORDER


@pytest.fixture(scope="module")
def fitted():
    motions = [synthetic_mmm(T=201, seed=0), synthetic_mmm(T=150, seed=1, height=1.6)]
    return AnglesFeatures().fit(motions), motions


def test_layout(fitted):
    f, _ = fitted
    assert f.dim == 44 + 6 + 1 and f.names[:44] == list(MMM_DOF_ORDER)
    assert f.names[-1] == "active" and f.fps == 10.0
    assert AnglesFeatures(root="none", active=False).dim == 44


def test_ten_offsets_pick_the_right_frames(fitted):
    f, (m, _) = fitted
    seqs = f.encode_all(m)
    assert len(seqs) == 10
    # 201 frames: offset 0 gets frames 0,10,..,200 (21), offsets 1..9 get 20
    assert [len(s) for s in seqs] == [21] + [20] * 9
    for k in (0, 3, 9):
        raw = f.normalizer.inverse(seqs[k][:, :-1].astype(float))
        for i in (0, 20, 43):
            assert np.allclose(raw[:, i], m.angle(MMM_DOF_ORDER[i])[k::10], atol=1e-5)
        assert np.all(seqs[k][:, -1] == 1.0)
    assert seqs[0].dtype == np.float32


def test_normalised_over_training_data(fitted):
    f, motions = fitted
    x = np.concatenate([s for m in motions for s in f.encode_all(m)]).astype(float)
    assert np.allclose(x[:, :-1].mean(0), 0, atol=1e-5)
    assert np.allclose(x[:, :-1].std(0), 1, atol=1e-4)


def test_decode_rebuilds_the_motion(fitted):
    f, (m, _) = fitted
    sub = m[3::10]
    # subject size is not a feature: decode on the subject's skeleton (default: mean height)
    out = f.decode(f.encode(m, 3), skeleton=m.skeleton, start=root_trajectory(sub)["start"])
    assert out.fps == 10.0 and len(out) == len(sub)
    assert np.abs(out.positions() - sub.positions()).max() < 1e-5
    # default placement: first frame's root at the ground origin
    p0 = f.decode(f.encode(m, 3)).positions()[0, 0]
    assert abs(p0[0]) < 1e-9 and abs(p0[2]) < 1e-9
    # features do not depend on where the subject stood or faced
    assert np.allclose(f.encode(turn(m, 2.0, -1.0, 3.0), 3), f.encode(m, 3), atol=1e-4)


def test_active_flag_ends_decoding(fitted):
    f, (m, m2) = fitted
    a, b = f.encode(m), f.encode(m2)
    batch, mask = pad_batch([a, b])
    assert len(f.decode(batch[1])) == len(b) == int(mask[1].sum()) < len(a)
    cut = a.copy()
    cut[7:, -1] = 0.2
    assert len(f.decode(cut)) == 7
    assert len(f.decode(np.zeros((5, f.dim)))) == 1  # never an empty motion


def test_root_none_stands_still():
    m = synthetic_mmm(T=101)
    f = AnglesFeatures(root="none").fit([m])
    out = f.decode(f.encode(m))
    assert np.allclose(out.root_translation, out.root_translation[0])
    assert np.allclose(out.joint_angles[:, 0], m.joint_angles[::10, 0], atol=1e-5)


def test_persistence_and_errors(fitted, tmp_path, tiny_motion):
    f, (m, _) = fitted
    f.save(tmp_path / "angles.json")
    path = tmp_path / "angles.json"
    for g in (AnglesFeatures.load(path), FeatureSet.load(path), features_from_dict(f.to_dict())):
        assert isinstance(g, AnglesFeatures)
        assert np.array_equal(g.encode(m, 2), f.encode(m, 2))
        assert g.subject_height == f.subject_height
    with pytest.raises(SkeletonError, match="MMM skeleton"):
        f.encode(tiny_motion)
    with pytest.raises(MotionlangError, match="not fitted"):
        AnglesFeatures().encode(m)
    with pytest.raises(MotionlangError, match=r"\(T, 51\)"):
        f.decode(np.zeros((3, 50)))


def test_real_kit_motion():
    m = read_mmm(shared_file("kitml/00001_mmm.xml"))
    f = AnglesFeatures().fit([m])
    seqs = f.encode_all(m)
    assert [len(s) for s in seqs] == [38] * 8 + [37] * 2  # 378 frames at 100 Hz
    sub = m[5::10]
    out = f.decode(seqs[5], start=root_trajectory(sub)["start"])
    assert np.abs(out.positions() - sub.positions()).max() < 1e-5


def test_short_motion_and_generator_fit():
    m = synthetic_mmm(T=3)
    f = AnglesFeatures().fit(x for x in [m, synthetic_mmm(T=40, seed=2)])
    assert [len(s) for s in f.encode_all(m)] == [1, 1, 1]

import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import synthetic_mmm, turn
from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features import PositionFeatures, downsample, features_from_dict
from motionlang.features.joint_map import KIT21_NAMES, positions21
from motionlang.features.positions import facing_yaw, floor_height
from motionlang.formats.asf_amc import read_asf_amc
from motionlang.formats.mmm import read_mmm

LH, LF, LA = (KIT21_NAMES.index(n) for n in ("LH", "LF", "LA"))


@pytest.fixture(scope="module")
def fitted():
    m = synthetic_mmm(T=301)
    return PositionFeatures().fit([m]), m


def test_layout_and_rate(fitted):
    f, m = fitted
    x = f.encode(m)
    assert f.dim == 66 and x.shape == (len(m[::8]), 66) and f.fps == 12.5
    assert f.names[:3] == ["root_x", "root_y", "root_z"] and f.names[-1] == "root_dyaw"


def test_round_trip_and_default_placement(fitted):
    f, m = fitted
    x = f.encode(m)
    ref = f.body(m)
    assert np.allclose(ref, positions21(m[::8]) - [0, floor_height(positions21(m[::8])), 0])
    assert np.abs(f.decode(x, start=f.start(m)) - ref).max() < 1e-5
    # default: frame 0's root over the origin, body facing +z
    out = f.decode(x)
    assert np.allclose(out[0, 0, [0, 2]], 0, atol=1e-9)
    assert abs(facing_yaw(out[:1])[0]) < 1e-5
    assert np.allclose(out[0, 0, 1], ref[0, 0, 1], atol=1e-5)


def test_local_frame_is_body_centred(fitted):
    f, m = fitted
    raw = f.normalizer.inverse(f.encode(m).astype(float)).reshape(-1, 66)
    local = raw[:, :63].reshape(-1, 21, 3)
    assert np.allclose(local[:, 0, [0, 2]], 0, atol=1e-6)   # root over the local origin
    assert np.all(local[:, LH, 0] > 0)                      # left hip on +x
    assert np.all(local[:, LF, 2] > local[:, LA, 2])         # toes ahead of the ankle
    # moving the subject elsewhere in the room changes nothing but the start
    moved = turn(m, -2.5, 4.0, 1.0)
    assert np.allclose(f.encode(moved), f.encode(m), atol=1e-4)


def test_persistence_and_errors(fitted, tmp_path, tiny_motion):
    f, m = fitted
    f.save(tmp_path / "pos.json")
    g = PositionFeatures.load(tmp_path / "pos.json")
    assert np.array_equal(g.encode(m), f.encode(m))
    assert isinstance(features_from_dict(f.to_dict()), PositionFeatures)
    with pytest.raises(SkeletonError, match="cannot be mapped"):
        f.encode(tiny_motion)
    with pytest.raises(MotionlangError, match=r"\(T, 66\)"):
        f.decode(np.zeros((2, 65)))


@pytest.mark.parametrize("which", ["kit", "cmu"])
def test_real_motion_round_trip(which):
    if which == "kit":
        m = read_mmm(shared_file("kitml/00001_mmm.xml"))
    else:  # 120 Hz -> 12.5 Hz is not an integer ratio: re-timed
        m = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    f = PositionFeatures().fit([m])
    x = f.encode(m)
    ref = f.body(m)
    assert np.allclose(ref[..., [0, 2]], positions21(downsample(m, 12.5))[..., [0, 2]])
    assert len(x) == int(np.floor((len(m) - 1) / m.fps * 12.5 + 1e-9)) + 1
    assert np.abs(f.decode(x, start=f.start(m)) - ref).max() < 1e-5
    raw = f.normalizer.inverse(x.astype(float))
    assert raw[:, 64].mean() * 12.5 > 0.3  # both subjects walk forwards (m/s)


def test_floor_moves_feet_onto_the_ground(fitted):
    f, m = fitted
    lifted = m.replace(root_translation=m.root_translation + [0, 0, 0.7])  # MMM: Z up
    p = f.body(lifted)
    assert abs(floor_height(p)) < 1e-9
    assert np.allclose(f.encode(lifted), f.encode(m), atol=1e-4)
    # the option off keeps the file's floor
    off = PositionFeatures(floor=False).fit([m])
    assert np.allclose(off.body(lifted)[..., 1] - off.body(m)[..., 1], 0.7)
    # files written before the option read back with it off
    d = f.to_dict()
    del d["config"]["floor"]
    assert features_from_dict(d).config.floor is False

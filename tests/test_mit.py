"""MIT walking data (Taylor's motion.mat): layout, a plausible walker, bad input."""
import numpy as np
import pytest
from scipy.io import savemat

from helpers.data import shared_file
from motionlang.errors import MotionFormatError
from motionlang.formats.mit import MIT_JOINT_NAMES, read_mit


@pytest.fixture(scope="module")
def mit():
    return read_mit(shared_file("mit/motion.mat"))


def test_sequences_and_layout(mit):
    assert [m.n_frames for m in mit] == [438, 260, 3128]
    assert all(m.fps == 30.0 and m.source_format == "mit" for m in mit)
    sk = mit[0].skeleton
    assert sk.names == list(MIT_JOINT_NAMES) and sk.ndof == 17 * 3
    assert all(m.skeleton is sk for m in mit)
    # bone lengths (mm in the file): thigh 399.43, shank 383.498, foot 178.197
    assert np.isclose(np.linalg.norm(sk.joints[sk.index("lknee")].offset), 0.39943)
    assert np.isclose(np.linalg.norm(sk.joints[sk.index("rankle")].offset), 0.383498)
    assert ("lhip", "rhip") in sk.pairs and ("lwrist", "rwrist") in sk.pairs
    # knees are hinges: only the Y (lateral) channel ever moves
    knee = mit[2].joint_angles[:, sk.dof_slice("lknee")]
    assert np.all(knee[:, [0, 2]] == 0) and knee[:, 1].max() > 1.0


def test_root_round_trip_to_file_values(mit):
    """The root rotation stored as yaw-pitch-roll rebuilds the file's matrix exactly."""
    from scipy.io import loadmat

    from motionlang.formats.mit import ROOT_AXES, root_matrix
    from motionlang.kinematics.rotations import axis_angle, chain

    raw = loadmat(str(shared_file("mit/motion.mat")))["Motion"][0, 1]
    R_file = root_matrix(raw[:, 0:3])
    # the convention written out: Q Rx(a) Rz(c) Ry(b) Q, Q the cycle x->y->z->x
    x, y, z = np.eye(3)
    Q = np.stack([y, z, x], axis=1)
    a, b, c = raw[5, 0:3]
    assert np.allclose(R_file[5], Q @ axis_angle(x, a) @ axis_angle(z, c) @ axis_angle(y, b) @ Q)
    assert np.allclose(root_matrix(np.array([np.pi / 2, np.pi / 2, 0.0])), np.eye(3))
    assert np.allclose(chain(ROOT_AXES, mit[1].root_rotation), R_file, atol=1e-9)
    assert np.allclose(mit[1].root_translation, raw[:, 3:6] / 1000.0)


@pytest.mark.parametrize("k", [0, 1, 2])
def test_plausible_upright_walker(mit, k):
    m = mit[k]
    sk = m.skeleton
    P = m.positions()  # canonical: Y up
    shoulders = P[:, [sk.index("lshoulder"), sk.index("rshoulder")], 1]
    assert 1.25 < np.median(shoulders) < 1.55  # the tree has no head
    pelvis = P[:, 0, 1]
    assert 0.75 < pelvis.min() and pelvis.max() < 0.95
    feet = [sk.index(n) for n in ("lankle", "ltoes", "rankle", "rtoes")]
    lowest = P[:, feet, 1].min(axis=1)
    # a foot on the floor: within 8 cm in 99% of frames (the data has a few glitches)
    assert np.percentile(np.abs(lowest), 99) < 0.08 and abs(np.median(lowest)) < 0.04
    # left is +X canonical for a body facing +Z
    assert np.median(P[:, sk.index("lhip"), 0] - P[:, sk.index("rhip"), 0]) > 0.15
    # the body faces +Z (toes ahead of the ankles) ...
    toe_ahead = P[:, sk.index("ltoes"), 2] - P[:, sk.index("lankle"), 2]
    assert np.median(toe_ahead) > 0.05
    # ... and walks forwards on the spot: the root stays within a metre while the foot on
    # the ground slides backwards at walking speed (treadmill-like)
    assert np.ptp(P[:, 0, 2]) < 1.0
    low = np.argmin(P[:, feet, 1], axis=1)
    v = np.diff(P[:, feet], axis=0)[np.arange(m.n_frames - 1), low[:-1]] * m.fps
    assert -1.6 < np.median(v[:, 2]) < -0.6
    # ... and hardly sideways (the root convention was chosen by this; see mit.py)
    assert np.median(np.abs(v[:, 0])) < 0.3


def test_mirror_swaps_legs(mit):
    m = mit[0][:20]
    q = m.mirror().positions()
    p = m.positions()
    sk = m.skeleton
    S = sk.world @ sk.mirror @ sk.world.T
    assert np.allclose(q[:, sk.index("lankle")], p[:, sk.index("rankle")] @ S.T, atol=1e-9)


def _cell(*arrays):
    """A MATLAB 1 x n cell array (np.array would broadcast same-shaped arrays instead)."""
    out = np.empty((1, len(arrays)), dtype=object)
    for i, a in enumerate(arrays):
        out[0, i] = a
    return out


def _mat(tmp_path, **variables):
    path = tmp_path / "bad.mat"
    savemat(str(path), variables)
    return path


def _tree(n=2):
    nodes = np.zeros((1, n), dtype=[("children", "O"), ("parent", "O"), ("or", "O"),
                                    ("offset", "O")])
    for i in range(n):
        nodes[0, i]["parent"] = np.zeros((0, 0)) if i == 0 else np.array([[i]], float)
        nodes[0, i]["children"] = np.array([[i + 2]], float) if i < n - 1 else np.zeros((0, 0))
        nodes[0, i]["or"] = np.array([[6 * i + 1, 6 * i + 2, 6 * i + 3]], float)
        nodes[0, i]["offset"] = np.array([[6 * i + 4, 6 * i + 5, 6 * i + 6]], float)
    skel = np.zeros((1, 1), dtype=[("tree", "O"), ("type", "O")])
    skel[0, 0]["tree"] = nodes
    skel[0, 0]["type"] = "mit"
    return skel


def _seq(T=4):
    X = np.zeros((T, 12))
    X[:, 0:2] = np.pi / 2  # standing root
    X[:, 5] = 900.0
    X[:, 11] = -400.0
    return X


def test_tiny_handmade_file(tmp_path):
    path = _mat(tmp_path, skel=_tree(), Motion=_cell(_seq(), _seq(3)))
    ms = read_mit(path)
    assert [m.n_frames for m in ms] == [4, 3]
    p = ms[0].positions()[0]
    assert np.allclose(p[0], [0, 0.9, 0]) and np.allclose(p[1], [0, 0.5, 0], atol=1e-9)


def test_bad_inputs(tmp_path):
    (tmp_path / "junk.mat").write_bytes(b"not a mat file at all")
    with pytest.raises(MotionFormatError, match="junk.mat"):
        read_mit(tmp_path / "junk.mat")
    with pytest.raises(MotionFormatError, match="'skel' and 'Motion'"):
        read_mit(_mat(tmp_path, skel=_tree()))
    wide = np.zeros((3, 13))
    with pytest.raises(MotionFormatError, match="expected"):
        read_mit(_mat(tmp_path, skel=_tree(), Motion=_cell(wide)))
    nan = _seq()
    nan[2, 7] = np.nan
    with pytest.raises(MotionFormatError) as info:
        read_mit(_mat(tmp_path, skel=_tree(), Motion=_cell(nan)))
    assert info.value.frame == 2
    moving = _seq()
    moving[1, 11] = -300.0  # a bone that changes length
    with pytest.raises(MotionFormatError, match="varies"):
        read_mit(_mat(tmp_path, skel=_tree(), Motion=_cell(moving)))
    with pytest.raises(MotionFormatError):
        read_mit(tmp_path / "missing.mat")


# ------------------------------------------------------------------ the MAT reader itself
def _element(mtype: int, payload: bytes, order: str = "<") -> bytes:
    pad = b"\0" * (-len(payload) % 8)
    return np.array([mtype, len(payload)], order + "u4").tobytes() + payload + pad


def _double_array(name: bytes, values, order: str = "<", data_type: int = 9) -> bytes:
    values = np.asarray(values, dtype=float)
    body = (_element(6, np.array([6, 0], order + "u4").tobytes(), order)      # double class
            + _element(5, np.array([1, values.size], order + "i4").tobytes(), order)
            + _element(1, name, order)
            + _element(data_type, values.astype(order + "f8").tobytes(), order))
    return _element(14, body, order)


def _mat_file(*elements: bytes, order: str = "<", version: int = 0x0100) -> bytes:
    head = b"MATLAB 5.0 MAT-file, hand-made".ljust(116) + b"\0" * 8
    head += version.to_bytes(2, "little" if order == "<" else "big")
    return head + (b"IM" if order == "<" else b"MI") + b"".join(elements)


@pytest.mark.parametrize("order", ["<", ">"])
def test_read_mat_both_byte_orders(tmp_path, order):
    from motionlang.formats.matfile import read_mat
    path = tmp_path / "x.mat"
    path.write_bytes(_mat_file(_double_array(b"x", [1.5, -2, 3], order), order=order))
    x = read_mat(path)["x"]
    assert x.shape == (1, 3) and x.dtype == float and x.tolist() == [[1.5, -2.0, 3.0]]


def test_read_mat_agrees_with_scipy_on_real_files():
    from scipy.io import loadmat

    from motionlang.formats.matfile import read_mat
    for rel in ("mit/motion.mat", "cmu35/cmu35WalkJog.mat"):
        ours, ref = read_mat(shared_file(rel)), loadmat(str(shared_file(rel)), mat_dtype=True)
        for k in ours:
            if ours[k].dtype != object:
                assert np.array_equal(ours[k], ref[k]), (rel, k)
    ours = read_mat(shared_file("mit/motion.mat"))
    ref = loadmat(str(shared_file("mit/motion.mat")), mat_dtype=True)
    assert all(np.array_equal(a, b) for a, b in zip(ours["Motion"].ravel(), ref["Motion"].ravel()))
    node, ref_node = ours["skel"][0, 0]["tree"][0, 3], ref["skel"][0, 0]["tree"][0, 3]
    assert all(np.array_equal(node[k], ref_node[k]) for k in ("parent", "or", "offset"))


@pytest.mark.parametrize("data, words", [
    # the crash: a double array's data tag says type 8 (scipy died with SIGSEGV)
    (_mat_file(_double_array(b"x", [1.0, 2.0], data_type=8)), "number data of element type 8"),
    (_mat_file(_double_array(b"x", [1.0, 2.0])[:-12]), "claims"),
    (_mat_file(_element(14, _element(6, b"\0" * 4))), "array flags"),
    (_mat_file(_element(99, b"12345678")), "unexpected element type 99"),
    (_mat_file(_element(15, b"not zlib at all")), "corrupt compressed"),
    (_mat_file(_double_array(b"x", [1.0]), version=0x0200), "v7.3"),
    (b"MATLAB 5.0 MAT-file" + b"\0" * 40, "not a MATLAB 5 MAT-file"),
])
def test_read_mat_refuses_malformed_files(tmp_path, data, words):
    from motionlang.formats.matfile import read_mat
    path = tmp_path / "bad.mat"
    path.write_bytes(data)
    with pytest.raises(MotionFormatError, match=words) as info:
        read_mat(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_read_mat_bounds_decompression(tmp_path, monkeypatch):
    import zlib

    from motionlang.formats.matfile import read_mat
    bomb = zlib.compress(_double_array(b"z", np.zeros(1 << 20)), 9)  # 8 MiB in ~8 KiB
    path = tmp_path / "bomb.mat"
    path.write_bytes(_mat_file(_element(15, bomb)))
    assert read_mat(path)["z"].size == 1 << 20
    monkeypatch.setenv("MOTIONLANG_MAX_MEMORY", "4M")
    with pytest.raises(MotionFormatError, match="MOTIONLANG_MAX_MEMORY"):
        read_mat(path)


@pytest.mark.parametrize("field, value, words", [
    ("parent", "text", "skel.tree(2).parent must be numbers, got text"),
    ("parent", np.array([[np.nan]]), "parent must be finite numbers"),
    ("parent", np.array([[1.5]]), "is not a parent listed before it"),
    ("or", "abc", "skel.tree(2).or must be numbers"),
    ("or", np.array([[1 + 2j, 2, 3]]), "or must be numbers"),
    ("offset", {"a": np.ones(3)}, "offset must be numbers, got a struct"),
    ("offset", np.array([[7.0, 8, 9, 10]]), "must be 3 column numbers"),
])
def test_wrong_field_types(tmp_path, field, value, words):
    tree = _tree()
    tree[0, 0]["tree"][0, 1][field] = value
    with pytest.raises(MotionFormatError, match=words.replace("(", r"\(").replace(")", r"\)")):
        read_mit(_mat(tmp_path, skel=tree, Motion=_cell(_seq())))


def test_wrong_motion_types_and_missing_fields(tmp_path):
    for motion, words in (("walk", "'Motion' must be a cell"), (_cell("walk"), "sequence 1 must "
                          "be numbers, got text"), (_cell(_seq() * 1e300), "out-of-range")):
        with pytest.raises(MotionFormatError, match=words):
            read_mit(_mat(tmp_path, skel=_tree(), Motion=motion))
    tree = _tree()
    nodes = np.zeros((1, 2), dtype=[(k, "O") for k in ("children", "parent", "or")])
    for k in nodes.dtype.names:
        nodes[0, 0][k], nodes[0, 1][k] = tree[0, 0]["tree"][0, 0][k], tree[0, 0]["tree"][0, 1][k]
    tree[0, 0]["tree"] = nodes
    with pytest.raises(MotionFormatError, match="has no 'offset' field"):
        read_mit(_mat(tmp_path, skel=tree, Motion=_cell(_seq())))
    with pytest.raises(MotionFormatError, match="'skel' must be a struct"):
        read_mit(_mat(tmp_path, skel="mit", Motion=_cell(_seq())))

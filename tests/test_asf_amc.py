"""ASF/AMC: the rotation convention by hand, real CMU subjects 35 and 49, the flat channel
layout against cmu35WalkJog.mat, AMC round trips, and every kind of bad input."""
import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import TINY_ASF, tiny_amc
from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.formats.asf_amc import (
    INCH,
    motion_from_channels,
    motion_to_channels,
    read_amc,
    read_asf,
    read_asf_amc,
    write_amc,
)


@pytest.fixture
def tiny(tmp_path):
    asf = tmp_path / "tiny.asf"
    asf.write_text(TINY_ASF)
    return read_asf(asf), tmp_path


def test_tiny_skeleton_layout(tiny):
    sk, _ = tiny
    assert sk.names == ["root", "chest", "larm", "larm_end", "rarm", "rarm_end"]
    assert sk.name == "cmu:tiny"
    assert sk.file_unit == pytest.approx(INCH)
    assert ("larm", "rarm") in sk.pairs
    # a node's offset is its parent bone's vector: larm starts at the end of chest
    assert np.allclose(sk.joints[sk.index("larm")].offset, [0, 10 * INCH, 0])
    assert np.allclose(sk.joints[sk.index("larm_end")].offset, [5 * INCH, 0, 0])
    # DOF chain stored in composition order: dof rx ry rz with axis XYZ -> Rz Ry Rx
    assert sk.joints[sk.index("chest")].dof_names == ("chest_rz", "chest_ry", "chest_rx")


def test_rotation_convention_by_hand(tiny):
    """dof rx ry rz means M = Rz Ry Rx (x applied first), bone frame C = Rz(90) for larm."""
    sk, tmp = tiny
    amc = tmp / "t.amc"
    amc.write_text(tiny_amc([([1, 2, 3, 0, 0, 0], [90, 0, 90], 90, 0)]))
    m = read_amc(amc, sk, fps=60)
    p = m.positions()[0]
    up = 10 * INCH
    chest_end = p[sk.index("larm")]  # larm starts at the chest's tip
    # Rx(90) takes (0,1,0) to (0,0,1); Rz(90) leaves it: tip at +z (Rx Rz would give -x)
    assert np.allclose(chest_end - p[0], [0, 0, up])
    assert np.allclose(p[0], np.array([1, 2, 3]) * INCH)
    # larm: local C Rx(90) C^T with C = Rz(90) turns about the chest frame's y axis;
    # chest frame = Rz(90) Rx(90), so compare against the explicit product
    Rz = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    Rx = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0.0]])
    arm = (Rz @ Rx) @ (Rz @ Rx @ Rz.T) @ np.array([5 * INCH, 0, 0])
    assert np.allclose(p[sk.index("larm_end")] - chest_end, arm)
    assert m.fps == 60 and m.source_format == "amc"


def test_radians_and_limits(tiny, tmp_path):
    """``angle rad`` applies to the ASF axis and to AMC values; limits are kept."""
    sk, _ = tiny
    assert sk.asf_layout["limits"]["chest"] == [(-180, 180)] * 3
    assert "rarm" not in sk.asf_layout["limits"]
    rad_asf = tmp_path / "rad.asf"
    rad_asf.write_text(TINY_ASF.replace("angle deg", "angle rad")
                       .replace("axis 0 0 90 XYZ", f"axis 0 0 {np.pi / 2} XYZ")
                       .replace("axis 0 0 -90 XYZ", f"axis 0 0 {-np.pi / 2} XYZ"))
    frame = ([1, 2, 3, 10, 20, 30], [40, -50, 60], 70, -80)
    (tmp_path / "deg.amc").write_text(tiny_amc([frame]))
    rad = (frame[0][:3] + list(np.deg2rad(frame[0][3:])), list(np.deg2rad(frame[1])),
           np.deg2rad(frame[2]), np.deg2rad(frame[3]))
    (tmp_path / "rad.amc").write_text(tiny_amc([rad]).replace(":DEGREES\n", ""))
    a = read_amc(tmp_path / "deg.amc", sk)
    b = read_amc(tmp_path / "rad.amc", read_asf(rad_asf))
    assert np.allclose(a.positions(), b.positions())


def test_channels_round_trip_tiny(tiny):
    sk, tmp = tiny
    rng = np.random.default_rng(1)
    ch = rng.uniform(-170, 170, (7, 11))
    m = motion_from_channels(sk, ch, 30.0)
    assert np.allclose(motion_to_channels(m), ch)
    write_amc(m, tmp / "out.amc")
    back = read_amc(tmp / "out.amc", sk, fps=30.0)
    assert np.abs(motion_to_channels(back) - ch).max() < 1e-4
    with pytest.raises(MotionFormatError):
        motion_from_channels(sk, ch[:, :10], 30.0)


def test_write_amc_needs_asf_skeleton(tiny_motion, tmp_path):
    with pytest.raises(SkeletonError):
        write_amc(tiny_motion, tmp_path / "x.amc")


# ------------------------------------------------------------------ real CMU data
def test_cmu35_walker_is_plausible():
    m = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    sk = m.skeleton
    assert m.n_frames == 358 and m.fps == 120.0 and sk.ndof == 56
    p = m.positions()
    feet = p[:, [sk.index(n) for n in ("ltoes", "rtoes", "lfoot", "rfoot")], 1]
    height = p[:, sk.index("head_end"), 1] - feet.min(axis=1)
    assert 1.5 < np.median(height) < 1.9
    assert -0.03 < feet.min() < 0.08            # on the ground, not floating or sunk
    assert np.all(p[:, sk.index("head"), 1] > p[:, 0, 1] + 0.4)   # upright every frame
    travel = p[-1, 0, [0, 2]] - p[0, 0, [0, 2]]
    assert np.linalg.norm(travel) > 2.5         # ~3 s of walking
    # the lowest foot barely slides (a wrong Euler order makes feet skate)
    low = np.argmin(feet[:, :2], axis=1)
    toes = p[:, [sk.index("ltoes"), sk.index("rtoes")]][np.arange(len(p)), low][:, [0, 2]]
    stance = (low[1:] == low[:-1]) & (feet[:-1, :2].min(axis=1) < feet[:, :2].min() + 0.02)
    speed = np.linalg.norm(np.diff(toes, axis=0), axis=1) * m.fps
    assert np.median(speed[stance]) < 0.2       # walking speed itself is ~1 m/s


@pytest.mark.parametrize("trial,frames", [("49_18", 1102), ("49_19", 957), ("49_20", 898)])
def test_cmu49_trials(trial, frames):
    sk = read_asf(shared_file("cmu49/49.asf"))
    m = read_amc(shared_file(f"cmu49/{trial}.amc"), sk)
    assert m.n_frames == frames
    p = m.positions()
    height = p[:, sk.index("head_end"), 1] - p[:, :, 1].min(axis=1)
    # subject 49 is small: 1.56 m from toes to the head bone's tip in the rest pose
    rest = motion_from_channels(sk, np.zeros((1, 62)), 120.0).positions()[0]
    assert rest[sk.index("head_end"), 1] - rest[:, 1].min() == pytest.approx(1.56, abs=0.01)
    assert 1.4 < np.median(height) < 1.7
    assert -0.05 < p[:, :, 1].min() < 0.1
    assert np.all(p[:, sk.index("head"), 1] > p[:, 0, 1] + 0.3)


def test_mat_columns_follow_asf_channel_order():
    """cmu35WalkJog.mat: 62 columns in 35.asf order; trial 35_01 = its first 90 rows."""
    scipy_io = pytest.importorskip("scipy.io")
    mat = scipy_io.loadmat(shared_file("cmu35/cmu35WalkJog.mat"))
    Y, lbls = mat["Y"], mat["lbls"]
    m = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    ch = motion_to_channels(m)
    assert ch.shape[1] == Y.shape[1] == 62
    n = int(lbls[:, 0].sum())
    assert n == len(ch[::4]) == 90
    assert np.abs(ch[::4] - Y[:n]).max() < 1e-4
    # and back: channels from the .mat make the same motion as the AMC
    m30 = motion_from_channels(m.skeleton, Y[:n], 30.0)
    assert np.allclose(m30.positions(), m[::4].positions(), atol=1e-6)


def test_real_amc_round_trip(tmp_path):
    sk = read_asf(shared_file("cmu35/35.asf"))
    m = read_amc(shared_file("cmu35/35_01.amc"), sk)
    write_amc(m, tmp_path / "35_01.amc")
    back = read_amc(tmp_path / "35_01.amc", sk)
    assert back.n_frames == m.n_frames
    assert np.abs(motion_to_channels(back) - motion_to_channels(m)).max() < 1e-4
    # and against the raw numbers of the original file, frame 1
    raw = {}
    for line in shared_file("cmu35/35_01.amc").read_text().splitlines()[4:34]:
        name, *vals = line.split()
        raw[name] = [float(v) for v in vals]
    written = dict((ln.split()[0], [float(v) for v in ln.split()[1:]])
                   for ln in (tmp_path / "35_01.amc").read_text().splitlines()[4:34])
    for name, vals in raw.items():
        assert np.allclose(written[name], vals, atol=1e-4), name


# ------------------------------------------------------------------ bad input
def _amc_lines(frames=2):
    return tiny_amc([([0, 0, 0, 0, 0, 0], [1, 2, 3], 4, 5)] * frames).splitlines()


@pytest.mark.parametrize("edit,line,words", [
    (lambda L: L[:-1], 11, "lacks bone"),                               # truncated
    (lambda L: L[:3] + ["root 0 0 zero 0 0 0"] + L[4:], 4, "malformed"),
    (lambda L: L[:4] + ["chest 1 2"] + L[5:], 5, "needs 3 values"),
    (lambda L: L[:5] + ["lram 4"] + L[6:], 6, "unknown bone"),
    (lambda L: L[:5] + ["larm nan"] + L[6:], 6, "non-finite"),
    (lambda L: L[:5] + ["larm 1e999"] + L[6:], 6, "non-finite"),
    (lambda L: L[:2], 2, "no frames"),
    (lambda L: L[:2] + L[4:], 3, "frame number"),
    (lambda L: L[:5] + ["chest 1 2 3"] + L[5:], 6, "twice"),
    (lambda L: L[:7] + ["9" * 5000] + L[8:], 8, "frame number 9999"),    # int() would raise
    (lambda L: L[:7] + ["\u00b2"] + L[8:], 8, "unknown bone '\u00b2'"),  # isdigit(), not int()
])
def test_bad_amc(tiny, edit, line, words):
    sk, tmp = tiny
    path = tmp / "bad.amc"
    path.write_text("\n".join(edit(_amc_lines())) + "\n")
    with pytest.raises(MotionFormatError) as info:
        read_amc(path, sk)
    assert info.value.line == line and words in str(info.value)
    assert str(path) in str(info.value)


def _asf_edit(old, new):
    assert old in TINY_ASF
    return TINY_ASF.replace(old, new)


@pytest.mark.parametrize("text,words", [
    (_asf_edit("    chest larm rarm\n", "    chest larm rarm\n    larm chest\n"), "two parents"),
    (_asf_edit("    root chest\n", "    root chest\n    rarm chest\n"), "two parents"),
    (_asf_edit("    root chest\n", "    larm chest\n"), "cycle"),
    (_asf_edit("    chest larm rarm\n", "    chest larm rarm\n    spine larm\n"), "unknown parent"),
    (_asf_edit("    chest larm rarm\n", "    chest larm rarm hand\n"), "unknown bone"),
    (_asf_edit("length 10", "length 1O"), "malformed"),
    (_asf_edit("direction 0 1 0", "direction 0 nan 0"), "non-finite"),
    (_asf_edit("direction 0 1 0", "direction 0 1"), "3 values"),
    (_asf_edit("dof rx\n    limits", "dof rx tx\n    limits"), "unsupported"),
    (TINY_ASF[:TINY_ASF.index(":hierarchy")], "no :hierarchy"),
    (TINY_ASF[:TINY_ASF.index("     name larm")], "missing 'end'"),
    (_asf_edit("name rarm", "name larm"), "duplicate"),
    (_asf_edit("(-180 180)\n  end", "(-180 180)\n           (0 1)\n  end"), "3 DOFs but 4 limits"),
    (_asf_edit("(-180 180)\n  end", "(-180 18O)\n  end"), "malformed limits"),
    (_asf_edit("(-180 180)\n  end", "(180 -180)\n  end"), "bad limits"),
    (_asf_edit(":bonedata\n", ":bonedata\n  limits (0 1)\n"), "outside begin/end"),
])
def test_bad_asf(tmp_path, text, words):
    path = tmp_path / "bad.asf"
    path.write_text(text)
    with pytest.raises(MotionFormatError) as info:
        read_asf(path)
    assert words in str(info.value) and info.value.line is not None
    assert str(path) in str(info.value)


def _chain_asf(n: int, child_first: bool) -> str:
    order = reversed(range(n)) if child_first else range(n)
    bones = "".join(f"begin\nname b{i}\ndirection 0 1 0\nlength 1\ndof rx\nend\n" for i in order)
    hier = "".join(f"b{i - 1} b{i}\n" if i else "root b0\n" for i in range(n))
    return f":units\nangle deg\n:bonedata\n{bones}:hierarchy\nbegin\n{hier}end\n"


def test_child_first_bone_list_is_not_quadratic(tmp_path, monkeypatch):
    """Bones listed child-before-parent cost n^2 (16,000: 36.7 s against 0.9 s parent
    first); now the order does not matter, and the node order is the same."""
    import time
    monkeypatch.setenv("MOTIONLANG_MAX_JOINTS", "10000")
    seconds, names = {}, {}
    for child_first in (False, True):
        path = tmp_path / f"chain{child_first}.asf"
        path.write_text(_chain_asf(4000, child_first))
        t0 = time.perf_counter()
        sk = read_asf(path)
        seconds[child_first], names[child_first] = time.perf_counter() - t0, sk.names
    assert names[True] == names[False] and len(names[True]) == 4002
    assert seconds[True] < 2 * seconds[False] + 0.5, seconds


def test_joint_limit(tmp_path, monkeypatch):
    path = tmp_path / "many.asf"
    path.write_text(_chain_asf(60, child_first=True))
    assert len(read_asf(path)) == 62
    monkeypatch.setenv("MOTIONLANG_MAX_JOINTS", "50")
    with pytest.raises(MotionFormatError, match="MOTIONLANG_MAX_JOINTS") as info:
        read_asf(path)
    assert info.value.line is not None and str(path) in str(info.value)


def test_missing_files(tmp_path, tiny):
    sk, _ = tiny
    with pytest.raises(MotionFormatError):
        read_asf(tmp_path / "nope.asf")
    with pytest.raises(MotionFormatError):
        read_amc(tmp_path / "nope.amc", sk)

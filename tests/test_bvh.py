"""BVH: reading by hand, exact round trips (hand-written and from a real AMC), any Motion
written Y-up (AMC, MMM) keeps its joint positions, units, and every kind of bad input."""
import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import HAND
from motionlang.errors import MotionFormatError
from motionlang.formats.bvh import guess_unit, read_bvh, write_bvh


def _values(text):
    """Frame values (T, C) and per-joint channel lists of a BVH text."""
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip().startswith("Frame Time"))
    chans = [ln.split()[2:] for ln in lines[:i] if ln.strip().startswith("CHANNELS")]
    return np.array([[float(v) for v in ln.split()] for ln in lines[i + 1:] if ln.split()]), chans


@pytest.fixture
def hand(tmp_path):
    path = tmp_path / "hand.bvh"
    path.write_text(HAND)
    return path


def test_read_hand_written(hand):
    m = read_bvh(hand)
    sk = m.skeleton
    assert sk.names == ["Hips", "LeftUpLeg", "LeftLeg", "LeftLeg_end", "RightUpLeg",
                        "RightUpLeg_end", "Chest", "Chest_end"]
    assert sk.file_unit == 0.01 and m.fps == 30.0 and m.n_frames == 3
    assert m.source_format == "bvh" and sk.name == "bvh:hand"
    assert np.allclose(sk.root_axes, np.eye(3)[[1, 0, 2]])
    assert np.allclose(sk.joints[2].axes, np.eye(3)[[0, 2]])
    assert sk.joints[2].dof_names == ("LeftLeg_Xrotation", "LeftLeg_Zrotation")
    assert np.allclose(m.root_translation[1], [0.015, 0.02, 0.0325])
    assert np.allclose(m.angle("LeftLeg_Zrotation"), np.deg2rad([0, 15, -15]))
    p = m.positions()
    # frame 0: root yaw 90 deg about +y sends the left hip (+x) to -z
    assert np.allclose(p[0, 0], [0.01, 0.92, 0.03])
    assert np.allclose(p[0, 1] - p[0, 0], [0, 0, -0.1])
    # right hip: Yrotation 90 first, so its leg (-y) stays -y after turning about y
    assert np.allclose(p[0, 5] - p[0, 4], [0, -0.9, 0])


def test_hand_written_round_trip_keeps_every_channel(hand, tmp_path):
    m = read_bvh(hand)
    write_bvh(m, tmp_path / "out.bvh")
    a, ca = _values(HAND)
    b, cb = _values((tmp_path / "out.bvh").read_text())
    assert ca == cb
    assert np.abs(a - b).max() < 1e-4
    back = read_bvh(tmp_path / "out.bvh")
    assert back.skeleton.names == m.skeleton.names
    assert np.allclose(back.positions(), m.positions(), atol=1e-9)


def test_units(hand, tmp_path):
    m = read_bvh(hand)
    for unit, name in ((1.0, "m"), (0.001, "mm"), ("cm", "cm")):
        write_bvh(m, tmp_path / f"{name}.bvh", unit=unit)
        back = read_bvh(tmp_path / f"{name}.bvh")
        assert np.allclose(back.positions(), m.positions(), atol=1e-6)
    assert read_bvh(tmp_path / "m.bvh").skeleton.file_unit == 1.0
    assert read_bvh(hand, unit="m").skeleton.file_unit == 1.0
    assert guess_unit(np.array([[0, 0, 0], [0, 1700, 0.0]])) == 0.001
    with pytest.raises(ValueError):
        write_bvh(m, tmp_path / "x.bvh", unit="furlong")


def test_amc_to_bvh_and_back(tmp_path):
    from motionlang.formats.asf_amc import read_asf_amc
    amc = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))[:60]
    write_bvh(amc, tmp_path / "a.bvh")
    text = (tmp_path / "a.bvh").read_text()
    assert "ROOT root" in text and "End Site" in text
    b = read_bvh(tmp_path / "a.bvh")
    assert b.skeleton.file_unit == 0.01        # centimetres for non-BVH motions
    assert b.fps == 120.0 and b.n_frames == 60
    idx = [b.skeleton.index(n) for n in amc.skeleton.names]
    assert np.abs(b.positions()[:, idx] - amc.positions()).max() < 1e-6
    # BVH -> Motion -> BVH keeps every channel
    write_bvh(b, tmp_path / "b.bvh")
    va, ca = _values(text)
    vb, cb = _values((tmp_path / "b.bvh").read_text())
    assert ca == cb and np.abs(va - vb).max() < 1e-4


def test_mmm_to_bvh_is_y_up(tmp_path):
    mmm = pytest.importorskip("motionlang.formats.mmm")
    m = mmm.read_mmm(shared_file("kitml/00001_mmm.xml"))[:50]
    write_bvh(m, tmp_path / "k.bvh")
    b = read_bvh(tmp_path / "k.bvh")
    common = [n for n in m.skeleton.names if n in b.skeleton]
    assert len(common) > 0.8 * len(m.skeleton)
    i = [m.skeleton.index(n) for n in common]
    j = [b.skeleton.index(n) for n in common]
    assert np.abs(m.positions()[:, i] - b.positions()[:, j]).max() < 1e-6
    # the rest pose itself is upright in Y (offsets were rotated into the Y-up frame)
    rest = b.replace(root_translation=np.zeros((50, 3)), root_rotation=np.zeros((50, 3)),
                     joint_angles=np.zeros_like(b.joint_angles)).positions()[0]
    assert 1.6 < np.ptp(rest[:, 1]) < 2.0 and np.ptp(rest[:, 2]) < 0.5


def test_constant_inner_position_channels(tmp_path):
    """LAFAN1-style files put constant position channels on every joint: accepted; a moving
    one is averaged (tests/test_bvh_wild.py has more)."""
    text = HAND.replace("    CHANNELS 3 Yrotation Zrotation Xrotation",
                        "    CHANNELS 6 Xposition Yposition Zposition "
                        "Yrotation Zrotation Xrotation")
    lines = text.splitlines()
    k = lines.index("MOTION") + 3
    frames = [lines[k + t].split() for t in range(3)]

    def write(x_of_frame):
        rows = [" ".join(v[:11] + [x, "0", "0"] + v[11:]) for v, x in zip(frames, x_of_frame)]
        (tmp_path / "l.bvh").write_text("\n".join(lines[:k] + rows) + "\n")

    write(["-20", "-20", "-20"])
    m = read_bvh(tmp_path / "l.bvh")
    assert np.allclose(m.skeleton.joints[m.skeleton.index("RightUpLeg")].offset, [-0.2, 0, 0])
    assert np.allclose(m.angle("RightUpLeg_Xrotation"), np.deg2rad([0, 3, -3]))
    assert m.meta["bvh_position_spread_m"] == {}
    # moving ones cannot be represented: their mean becomes the offset, the spread is kept
    write(["-20", "-21", "-20"])
    m = read_bvh(tmp_path / "l.bvh")
    assert np.allclose(m.skeleton.joints[m.skeleton.index("RightUpLeg")].offset,
                       [-0.61 / 3, 0, 0])
    assert m.meta["bvh_position_spread_m"] == pytest.approx({"RightUpLeg": 0.02 / 3})


# ------------------------------------------------------------------ bad input
def _edit(old, new, count=1):
    assert old in HAND
    return HAND.replace(old, new, count)


@pytest.mark.parametrize("text,line,words", [
    (HAND[:HAND.rindex("2 2 3.5")], 43, "truncated"),
    (HAND[:HAND.index("  JOINT Chest")], 28, "ends early"),
    (_edit("1.5 2 3.25", "1.5 2 3.2.5"), 43, "malformed"),
    (_edit("1.5 2 3.25 ", "1.5 2 "), 43, "values, expected 17"),
    (_edit("1.5 2 3.25", "1.5 nan 3.25"), 43, "non-finite"),
    (_edit("Frames: 3", "Frames: 0"), 41, "no frames"),
    (_edit("Frames: 3", "Frames: 2"), 44, "more frame lines"),
    (_edit("Frames: 3", "Frames: three"), 40, "malformed"),
    (_edit("Frame Time: 0.0333333", "Frame Time: -1"), 41, "positive"),
    (_edit("OFFSET 10 0 0", "OFFSET 10 0 x"), 8, "malformed"),
    (_edit("OFFSET 10 0 0", "OFFSET 10 0 1e999"), 8, "non-finite"),
    (_edit("Xrotation Yrotation Zrotation", "Xrotation Yrotation Wrotation"), 9, "channel"),
    (_edit("CHANNELS 2 Xrotation Zrotation", "CHANNELS 9 Xrotation Zrotation"), 13, "count"),
    (_edit("        OFFSET 0 -45 0\n      }",
           "        OFFSET 0 -45 0\n        CHANNELS 1 Xrotation\n      }"), 17, "End Site"),
    (_edit("  JOINT LeftUpLeg", "  BONE LeftUpLeg"), 6, "unexpected"),
    (_edit("JOINT Chest", "JOINT LeftLeg"), 29, "duplicate"),
])
def test_bad_bvh(tmp_path, text, line, words):
    path = tmp_path / "bad.bvh"
    path.write_text(text)
    with pytest.raises(MotionFormatError) as info:
        read_bvh(path)
    assert words in str(info.value)
    assert info.value.line == line
    assert str(path) in str(info.value)


def test_missing_bvh(tmp_path):
    with pytest.raises(MotionFormatError, match="cannot read"):
        read_bvh(tmp_path / "none.bvh")


def test_written_layout_is_the_plain_one_blender_reads(tiny_motion, tmp_path):
    """A non-BVH motion: root 6 channels (positions first), 3 ZXY rotations per joint,
    End Sites without channels, balanced braces, one line of values per frame."""
    write_bvh(tiny_motion, tmp_path / "t.bvh")
    lines = [ln.strip() for ln in (tmp_path / "t.bvh").read_text().splitlines()]
    assert lines[0] == "HIERARCHY" and lines[1] == "ROOT Hips"
    assert lines[4] == "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
    motion_at = lines.index("MOTION")
    head = lines[:motion_at]
    assert head.count("{") == head.count("}") == sum(ln.startswith(("ROOT", "JOINT", "End"))
                                                     for ln in head)
    for i, ln in enumerate(head):
        if ln.startswith("JOINT"):
            assert head[i + 2].startswith("OFFSET")
            assert head[i + 3] == "CHANNELS 3 Zrotation Xrotation Yrotation"
        if ln == "End Site":
            assert head[i + 2].startswith("OFFSET") and head[i + 3] == "}"
    n_channels = sum(int(ln.split()[1]) for ln in head if ln.startswith("CHANNELS"))
    assert lines[motion_at + 1] == f"Frames: {tiny_motion.n_frames}"
    assert lines[motion_at + 2] == "Frame Time: 0.03333333"
    rows = lines[motion_at + 3:]
    assert len(rows) == tiny_motion.n_frames
    assert all(len(r.split()) == n_channels for r in rows)


def test_windows_line_ends_and_bom(hand, tmp_path):
    path = tmp_path / "win.bvh"
    path.write_bytes(b"\xef\xbb\xbf" + HAND.replace("\n", "\r\n").encode())
    assert np.array_equal(read_bvh(path).joint_angles, read_bvh(hand).joint_angles)


def test_limits_are_checked_before_reading_the_numbers(tmp_path, monkeypatch):
    """A 2 MB file declaring 9,990 nested joints and a million frames asked numpy for
    447 GiB; the joints, frames and memory a file asks for are now checked first."""
    path = tmp_path / "big.bvh"
    head = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n" + "".join(
        f"JOINT j{i}\n{{\nOFFSET 0 1 0\nCHANNELS 0\n" for i in range(1, 9990))
    path.write_text(head + "End Site\n{\nOFFSET 0 1 0\n}\n" + "}\n" * 9990
                    + "MOTION\nFrames: 1000000\nFrame Time: 0.01\n" + "0\n" * 1_000_000)
    with pytest.raises(MotionFormatError, match="joint count 2,001 exceeds the limit of 2,000 "
                                                r"\(raise it with MOTIONLANG_MAX_JOINTS=...\)"):
        read_bvh(path)
    monkeypatch.setenv("MOTIONLANG_MAX_JOINTS", "20000")
    with pytest.raises(MotionFormatError, match="memory needed for 1,000,000 frames of 9,991 "
                                                "joints .* exceeds .*MOTIONLANG_MAX_MEMORY"):
        read_bvh(path)
    monkeypatch.setenv("MOTIONLANG_MAX_FRAMES", "999999")
    with pytest.raises(MotionFormatError, match="frame count 1,000,000 exceeds"):
        read_bvh(path)
    monkeypatch.setenv("MOTIONLANG_MAX_FILE_BYTES", "1M")
    with pytest.raises(MotionFormatError, match="file size .* exceeds the limit of 1 MiB"):
        read_bvh(path)


def test_huge_declared_frame_counts(tmp_path):
    for frames in ("1000000000000", "9" * 5000, "\u00b2"):
        path = tmp_path / "f.bvh"
        path.write_text(_edit("Frames: 3", f"Frames: {frames}"), encoding="utf-8")
        with pytest.raises(MotionFormatError, match="frame count|malformed") as info:
            read_bvh(path)
        assert "\n" not in str(info.value)

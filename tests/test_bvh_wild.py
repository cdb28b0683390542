"""BVH as it exists in the wild: position channels on inner joints (constant, noisy,
animated), any channel order per joint, named End Sites, rounded frame times, ``Frames:``
that disagree with the lines, units decided from the body (cm, m, mm, inch, "BVH units",
a rest pose that is not standing), re-rooting under a root that does not carry the body,
writing back in the file's own layout, and real Bandai Namco takes."""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from helpers.data import bandai_takes, shared_file
from motionlang.errors import MotionFormatError
from motionlang.formats import motion_info
from motionlang.formats.bvh import read_bvh, write_bvh
from motionlang.kinematics.rotations import AXES, chain, matrix_to_chain

ROT = ["Zrotation", "Xrotation", "Yrotation"]
POS = ["Xposition", "Yposition", "Zposition"]


# ------------------------------------------------------------------ a tiny BVH writer
def _text(root, frames, frame_time="0.0333333") -> str:
    """BVH text of a node tree; a node is ``(name, offset, channels, children)`` or
    ``("End", site_name_or_None, offset)``."""
    out = ["HIERARCHY"]

    def emit(node, depth):
        ind = "  " * depth
        if node[0] == "End":
            out.extend([f"{ind}End Site" + (f" {node[1]}" if node[1] else ""), ind + "{",
                        f"{ind}  OFFSET {' '.join(map(str, node[2]))}", ind + "}"])
            return
        name, offset, channels, children = node
        out.extend([f"{ind}{'ROOT' if depth == 0 else 'JOINT'} {name}", ind + "{",
                    f"{ind}  OFFSET {' '.join(map(str, offset))}",
                    f"{ind}  CHANNELS {len(channels)} {' '.join(channels)}"])
        for child in children:
            emit(child, depth + 1)
        out.append(ind + "}")

    emit(root, 0)
    out += ["MOTION", f"Frames: {len(frames)}", f"Frame Time: {frame_time}"]
    out += [" ".join(f"{v:.10g}" for v in row) for row in frames]
    return "\n".join(out) + "\n"


def _human(scale=1.0, folded=False, leg_channels=None):
    """A 1.71 m body (thigh + shank 84 cm = 0.491 of 171 cm) in ``scale`` x centimetres.

    ``folded``: every bone lies along local +X in the rest pose (as in Bandai Namco's rig),
    and the frames' rotations stand the body up. Returns (tree, frames (4, C))."""
    s = lambda *v: [x * scale for x in v]  # noqa: E731
    along = (lambda n: s(n, 0, 0)) if folded else None
    legs = []
    for side, x in (("Left", 10), ("Right", -10)):
        hip = s(0, 0, x) if folded else s(x, 0, 0)
        down = along(42) if folded else s(0, -42, 0)
        toe = along(4) if folded else s(0, -4, 12)
        chans = (leg_channels or {}).get(side, ROT)
        legs.append((f"{side}UpLeg", hip, ROT, [
            (f"{side}Leg", down, chans, [(f"{side}Foot", down, ROT, [("End", None, toe)])])]))
    spine = ("Spine", along(10) if folded else s(0, 10, 0), ROT, [
        ("Head", along(50) if folded else s(0, 50, 0), ROT,
         [("End", None, along(20) if folded else s(0, 20, 0))])])
    tree = ("Hips", [0, 0, 0], POS + ROT, [spine] + legs)
    frames = []
    for t in range(4):
        swing = 20.0 * (-1) ** t
        hips = s(0, 88, 5 * t) + [90.0 if folded else 0.0, 0.0, 0.0]
        up = [180.0 if folded else 0.0, swing, 0.0]
        knee = [0.0, 10.0, 0.0]
        frames.append(hips + [0, 5 * t, 0] + [0, 0, 0] + up + knee + [0, 0, 0]
                      + [up[0], -swing, 0.0] + knee + [0, 0, 0])
    return tree, np.array(frames, dtype=float)


def _write(tmp_path, name, tree, frames, **kw):
    path = tmp_path / name
    path.write_text(_text(tree, frames, **kw))
    return path


# ------------------------------------------------------------------ units
@pytest.mark.parametrize("unit,scale", [("cm", 1.0), ("m", 0.01), ("mm", 10.0),
                                        ("inch", 1 / 2.54)])
@pytest.mark.parametrize("folded", [False, True])
def test_unit_from_the_body(tmp_path, unit, scale, folded):
    tree, frames = _human(scale, folded)
    m = read_bvh(_write(tmp_path, "h.bvh", tree, frames))
    assert m.meta["unit"] == unit and "unit_note" not in m.meta
    assert m.skeleton.file_unit == pytest.approx({"cm": 0.01, "m": 1, "mm": 0.001,
                                                  "inch": 0.0254}[unit])
    assert m.meta["stature_m"] == pytest.approx(0.84 / 0.491, rel=1e-6)
    p = m.positions()
    assert np.allclose(p[0, m.skeleton.index("Hips")], [0, 0.88, 0], atol=1e-9)
    # the posed body stands even when the rest pose lies along X
    assert 1.5 < np.ptp(p[0, :, 1]) < 1.7


def test_folded_rest_pose_is_not_read_as_a_small_body(tmp_path):
    """In inches, the folded rest pose spans 35 units: a rest-pose guess calls that
    centimetres (a 0.35 m body); the posed legs say inches."""
    tree, frames = _human(1 / 2.54, folded=True)
    path = _write(tmp_path, "f.bvh", tree, frames)
    rest = read_bvh(path, unit="m")
    rest = rest.replace(root_rotation=0 * rest.root_rotation,
                        joint_angles=0 * rest.joint_angles).positions()[0]
    assert np.ptp(rest, axis=0).max() < 36
    assert read_bvh(path).meta["unit"] == "inch"


def test_bvh_units_are_scaled_to_a_human(tmp_path):
    """A body 30 units tall (CMU's ASF unit, 1/0.45 inch): no unit makes it human."""
    tree, frames = _human(30 / (84 / 0.491))
    m = read_bvh(_write(tmp_path, "a.bvh", tree, frames))
    assert m.meta["unit"] == "BVH units" and "1.75 m" in m.meta["unit_note"]
    assert m.meta["stature_m"] == pytest.approx(1.75)
    assert m.skeleton.file_unit == pytest.approx(1.75 / 30)


def test_explicit_unit_wins(tmp_path):
    tree, frames = _human()
    m = read_bvh(_write(tmp_path, "h.bvh", tree, frames), unit="mm")
    assert m.meta["unit"] == "mm" and m.meta["unit_note"] == "given by the caller"
    assert m.meta["stature_m"] == pytest.approx(0.171, rel=1e-3)
    with pytest.raises(ValueError, match="unknown unit"):
        read_bvh(tmp_path / "h.bvh", unit="furlong")


# ------------------------------------------------------------------ position channels
def test_inner_position_channels_constant_and_animated(tmp_path):
    six = POS + ROT
    tree, frames = _human(leg_channels={"Left": six, "Right": six})
    # the knees' OFFSETs are garbage: their position channels say where the knees are
    for k, side in ((1, "Left"), (2, "Right")):
        kids = tree[3][k][3]
        kids[0] = (f"{side}Leg", [7, 7, 7], six, kids[0][3])
    cols = list(frames.T)
    # columns: Hips 6, Spine 3, Head 3, LeftUpLeg 3, | LeftLeg positions | ...; the left
    # knee's channels are constant up to float noise, the right one's move by 2 cm
    cols[15:15] = [np.zeros(4), np.full(4, -42.0) + 1e-9 * np.arange(4), np.full(4, 1e-8)]
    cols[27:27] = [np.zeros(4), -42.0 + np.array([0.0, 2.0, 0.0, -2.0]), np.zeros(4)]
    m = read_bvh(_write(tmp_path, "p.bvh", tree, np.stack(cols, axis=1)), unit="cm")
    sk = m.skeleton
    assert np.allclose(sk.joints[sk.index("LeftLeg")].offset, [0, -0.42, 0], atol=1e-9)
    assert np.allclose(sk.joints[sk.index("RightLeg")].offset, [0, -0.42, 0])
    assert m.meta["bvh_position_spread_m"] == pytest.approx({"RightLeg": 0.02})
    assert m.angle("LeftLeg_Xrotation") == pytest.approx(np.deg2rad([10] * 4))
    # written back: position channels hold the offset, channel lists stay
    write_bvh(m, tmp_path / "o.bvh")
    back = read_bvh(tmp_path / "o.bvh", unit="cm")
    assert np.abs(back.positions() - m.positions()).max() < 1e-9
    assert "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" in \
        (tmp_path / "o.bvh").read_text().split("JOINT LeftLeg")[1]


def test_any_channel_order_per_joint(tmp_path):
    """Interleaved root channels, a different rotation order on every joint, a joint with
    two rotations and a joint with a lone position channel."""
    tree = ("Hips", [0, 90, 0], ["Yrotation", "Xposition", "Zrotation", "Yposition",
                                 "Xrotation", "Zposition"], [
        ("LeftUpLeg", [10, 0, 0], ["Xrotation", "Zrotation", "Yrotation"], [
            ("LeftLeg", [0, -45, 0], ["Zrotation", "Yposition", "Xrotation"],
             [("End", None, [0, -45, 0])])]),
        ("Spine", [0, 10, 0], ["Yrotation", "Xrotation"], [("End", None, [0, 60, 0])])])
    # frame 0: Hips yaw 90 (+x -> -z), LeftUpLeg Z 90 (-y -> +x), LeftLeg Y position -40
    # (-45 in frame 1: the mean, -42.5, becomes the offset)
    frames = [[90, 1, 0, 2, 0, 3, 0, 90, 0, 0, -40, 0, 0, 0],
              [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, -45, 0, 30, 90]]
    path = _write(tmp_path, "o.bvh", tree, frames)
    m = read_bvh(path, unit="cm")
    sk = m.skeleton
    assert np.allclose(sk.root_axes, np.stack([AXES["y"], AXES["z"], AXES["x"]]))
    assert sk.joints[sk.index("Spine")].dof_names == ("Spine_Yrotation", "Spine_Xrotation")
    p = m.positions() * 100
    hips, hip, knee, foot = (sk.index(n) for n in ("Hips", "LeftUpLeg", "LeftLeg",
                                                   "LeftLeg_end"))
    assert np.allclose(p[0, hips], [1, 92, 3])
    assert np.allclose(p[0, hip] - p[0, hips], [0, 0, -10])
    # the thigh (-y) turned to +x about the hip's z, then to -z by the yaw
    assert np.allclose(p[0, knee] - p[0, hip], [0, 0, -42.5])
    assert np.allclose(p[0, foot] - p[0, knee], [0, 0, -45])
    assert m.meta["bvh_position_spread_m"] == pytest.approx({"LeftLeg": 0.025})
    write_bvh(m, tmp_path / "back.bvh")
    heads = [ln.split() for ln in (tmp_path / "back.bvh").read_text().splitlines()
             if "CHANNELS" in ln]
    assert heads == [ln.split() for ln in path.read_text().splitlines() if "CHANNELS" in ln]


def test_named_end_sites(tmp_path):
    tree, frames = _human()
    text = _text(tree, frames).replace("End Site\n", "End Site LeftToe_Tip\n", 2)
    text = text.replace("End Site LeftToe_Tip\n", "End Site\n", 1)  # the head's stays bare
    (tmp_path / "n.bvh").write_text(text)
    m = read_bvh(tmp_path / "n.bvh")
    assert "Head_end" in m.skeleton and "LeftToe_Tip" in m.skeleton
    assert "RightFoot_end" in m.skeleton
    assert m.meta["bvh_hierarchy"]["nodes"][m.skeleton.index("LeftToe_Tip")]["name"] == \
        "LeftToe_Tip"
    write_bvh(m, tmp_path / "o.bvh")
    written = (tmp_path / "o.bvh").read_text()
    assert written.count("End Site LeftToe_Tip") == 1 and written.count("End Site\n") == 2
    assert read_bvh(tmp_path / "o.bvh").skeleton.names == m.skeleton.names


# ------------------------------------------------------------------ frames
@pytest.mark.parametrize("frame_time,fps", [("0.0333", 30.0), ("0.033333", 30.0),
                                            ("0.0333333", 30.0), ("0.0083333", 120.0),
                                            ("0.00833", 120.0), ("0.0166667", 60.0),
                                            ("0.04", 25.0), ("0.033", 1 / 0.033)])
def test_frame_time_rounding(tmp_path, frame_time, fps):
    tree, frames = _human()
    m = read_bvh(_write(tmp_path, "t.bvh", tree, frames, frame_time=frame_time))
    assert m.fps == pytest.approx(fps, rel=1e-12)
    assert m.meta["frame_time"] == float(frame_time)
    write_bvh(m, tmp_path / "o.bvh")
    assert f"Frame Time: {frame_time}\n" in (tmp_path / "o.bvh").read_text()


def _frame_time_line(text: str) -> int:
    """1-based number of the ``Frame Time`` line."""
    return next(i for i, ln in enumerate(text.splitlines(), 1) if ln.startswith("Frame Time"))


@pytest.mark.parametrize("count,words", [(3, "more frame lines than 'Frames: 3'"),
                                         (5, "file truncated: 4 of 5 frames")])
def test_frames_disagreeing_with_the_lines(tmp_path, count, words):
    """Either way the error names the 4th frame line (the one too many, or the last)."""
    tree, frames = _human()
    text = _text(tree, frames).replace("Frames: 4", f"Frames: {count}")
    (tmp_path / "f.bvh").write_text(text)
    with pytest.raises(MotionFormatError) as info:
        read_bvh(tmp_path / "f.bvh")
    assert words in str(info.value) and info.value.line == _frame_time_line(text) + 4
    assert str(tmp_path / "f.bvh") in str(info.value)


def test_blank_lines_between_frames_and_bad_values(tmp_path):
    tree, frames = _human()
    text = _text(tree, frames)
    k = _frame_time_line(text)             # frames on lines k + 1 ... k + 4
    lines = text.splitlines()
    lines.insert(k + 1, "  \t ")           # a blank line after the first frame
    (tmp_path / "b.bvh").write_text("\n".join(lines) + "\n")
    assert read_bvh(tmp_path / "b.bvh").n_frames == 4
    lines[k + 2] = lines[k + 2].replace("88", "8x8", 1)   # the second frame, line k + 3
    (tmp_path / "b.bvh").write_text("\n".join(lines) + "\n")
    with pytest.raises(MotionFormatError, match="malformed number '8x8'") as info:
        read_bvh(tmp_path / "b.bvh")
    assert info.value.line == k + 3


# ------------------------------------------------------------------ re-rooting
def _reference_rig(ref_yaw=90.0):
    """A ``Reference`` node above ``Hips`` (as Bandai Namco's ``joint_Root``), moved and
    turned: Reference at x = 100 cm, yawed ``ref_yaw``; Hips at (0, 90, 10 t) below it."""
    tree = ("Reference", [0, 0, 0], POS + ["Yrotation", "Xrotation", "Zrotation"], [
        ("Hips", [5, 5, -452], POS + ROT, [
            ("Spine", [10, 0, 0], ROT, [("End", None, [0, 10, 0])]),
            ("Leg", [0, -80, 0], ROT, [("End", None, [0, -10, 0])])])])
    frames = [[100, 0, 0, ref_yaw, 0, 0, 0, 90, 10 * t, 0, 0, -90 * t, 0, 0, 0, 0, 0, 0]
              for t in range(2)]
    return tree, frames


def test_reroot_composes_the_dropped_ancestors(tmp_path):
    path = _write(tmp_path, "r.bvh", *_reference_rig())
    m = read_bvh(path, unit="cm")
    sk = m.skeleton
    assert sk.names[0] == "Hips" and "Reference" not in sk
    assert m.meta["bvh_hierarchy"]["dropped"] == ["Reference"]
    assert m.meta["bvh_hierarchy"]["nodes"][0]["values"] == [100, 0, 0, 90, 0, 0]
    p = m.positions() * 100
    # yaw 90 sends (x, y, z) to (z, y, -x): Hips (0, 90, 10 t) lands at (100 + 10 t, 90, 0)
    assert np.allclose(p[:, 0], [[100, 90, 0], [110, 90, 0]])
    # frame 0: Spine's +x bone turned to -z; frame 1: Hips yaw -90 undoes the Reference's
    assert np.allclose(p[:, sk.index("Spine")] - p[:, 0], [[0, 0, -10], [10, 0, 0]])
    assert np.allclose(p[:, sk.index("Leg_end")] - p[:, 0], [[0, -90, 0], [0, -90, 0]])
    # back in the file's layout, every value as it was
    write_bvh(m, tmp_path / "o.bvh")
    a, b = path.read_text().split("MOTION"), (tmp_path / "o.bvh").read_text().split("MOTION")
    assert a[0].split() == b[0].replace("\t", " ").split()
    va = np.array([r.split() for r in a[1].splitlines()[3:]], dtype=float)
    vb = np.array([r.split() for r in b[1].splitlines()[3:]], dtype=float)
    assert np.abs(va - vb).max() < 1e-6


def test_reroot_under_a_still_reference_keeps_the_file_angles(tmp_path):
    path = _write(tmp_path, "r.bvh", *_reference_rig(ref_yaw=0.0))
    m = read_bvh(path, unit="cm")
    assert np.array_equal(m.root_rotation, np.deg2rad([[0, 0, 0], [0, 0, -90]]))
    assert np.allclose(m.root_translation * 100, [[100, 90, 0], [100, 90, 10]])


def test_no_reroot_when_the_chain_branches(tmp_path):
    tree, frames = _human()
    m = read_bvh(_write(tmp_path, "h.bvh", tree, frames))
    assert m.skeleton.names[0] == "Hips" and m.meta["bvh_hierarchy"]["dropped"] == []


# ------------------------------------------------------------------ real Bandai Namco takes
TAKES = ("walk_normal_001", "dash_normal_001", "bow_active_001")


@pytest.fixture(scope="module")
def bandai(tmp_path_factory):
    """A few dataset-1 takes extracted from the archive (never from a copy in the repo)."""
    return bandai_takes(TAKES, tmp_path_factory.mktemp("bandai"))


@pytest.mark.parametrize("take", TAKES)
def test_bandai_reads_as_a_standing_body(bandai, take):
    m = read_bvh(bandai / f"{take}.bvh")
    sk = m.skeleton
    assert m.fps == 30.0 and m.meta["frame_time"] == pytest.approx(1 / 30, rel=1e-5)
    assert m.meta["unit"] == "cm" and sk.file_unit == 0.01
    assert 1.5 < m.meta["stature_m"] < 1.9
    assert sk.names[0] == "Hips" and m.meta["bvh_hierarchy"]["dropped"] == ["joint_Root"]
    assert m.meta["bvh_position_spread_m"] == {}
    p = m.positions()
    toes = [sk.index("Toes_L"), sk.index("Toes_R")]
    assert -0.03 < np.median(p[:, toes, 1].min(axis=1)) < 0.08      # feet on the floor
    assert 0.75 < np.median(p[:, 0, 1]) < 1.0                        # hips at hip height
    head = p[:, sk.index("Head"), 1] - p[:, 0, 1]
    assert np.median(head) > 0.2                                     # upright
    # joint_Root jumps in some takes (dash) while Hips jumps back: the body does not
    assert np.linalg.norm(np.diff(m.root_translation, axis=0), axis=1).max() < 0.3


def test_bandai_walk_moves_forward(bandai):
    m = read_bvh(bandai / "walk_normal_001.bvh")
    travel = m.root_translation[-1] - m.root_translation[0]
    assert np.hypot(travel[0], travel[2]) > 3.0 and abs(travel[1]) < 0.1
    assert 0.5 < np.hypot(travel[0], travel[2]) / m.duration < 2.0   # m/s


@pytest.mark.parametrize("take", TAKES)
def test_bandai_write_read_round_trip(bandai, tmp_path, take):
    path = bandai / f"{take}.bvh"
    m = read_bvh(path)
    write_bvh(m, tmp_path / "o.bvh")
    back = read_bvh(tmp_path / "o.bvh")
    assert back.skeleton.names == m.skeleton.names
    assert np.abs(back.positions() - m.positions()).max() < 1e-6
    # the same hierarchy: names, End Sites, channel lists and OFFSET values
    orig = path.read_text().split("MOTION")[0].split()
    new = (tmp_path / "o.bvh").read_text().split("MOTION")[0].split()
    assert len(orig) == len(new)
    for x, y in zip(orig, new):
        try:
            assert float(x) == pytest.approx(float(y), rel=1e-8, abs=1e-12)
        except ValueError:
            assert x == y
    assert back.meta["bvh_hierarchy"]["nodes"] == m.meta["bvh_hierarchy"]["nodes"] or \
        take == "dash_normal_001"   # its moving joint_Root is written still
    # in metres too
    write_bvh(m, tmp_path / "m.bvh", unit="m")
    in_m = read_bvh(tmp_path / "m.bvh")
    assert in_m.meta["unit"] == "m"
    assert np.abs(in_m.positions() - m.positions()).max() < 1e-6


def test_bandai_motion_on_the_users_rig_with_other_root_axes(bandai, tmp_path):
    """What a retargeter produces: the user's skeleton and meta, but its own root chain
    (XYZ) and new angles; the writer converts to the file's channel order."""
    m = read_bvh(bandai / "bow_active_001.bvh")[:20]
    xyz = np.eye(3)
    R = chain(m.skeleton.root_axes, m.root_rotation)
    other = m.replace(skeleton=replace(m.skeleton, root_axes=xyz),
                      root_rotation=matrix_to_chain(R, xyz),
                      joint_angles=m.joint_angles * 0.5)
    write_bvh(other, tmp_path / "o.bvh")
    back = read_bvh(tmp_path / "o.bvh")
    assert np.abs(back.positions() - other.positions()).max() < 1e-6
    assert "JOINT Hips" in (tmp_path / "o.bvh").read_text()


# ------------------------------------------------------------------ info
def test_motion_info_reports_unit_and_stature(tmp_path, capsys):
    from motionlang.cli.main import main
    tree, frames = _human(1 / 2.54)
    path = _write(tmp_path, "h.bvh", tree, frames)
    info = motion_info(read_bvh(path))
    assert info["unit"] == "inch" and info["stature_m"] == pytest.approx(1.711, abs=1e-3)
    assert main(["info", str(path)]) == 0
    assert "1.71 m tall; lengths in inch" in capsys.readouterr().out
    assert main(["info", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["unit"] == "inch"


def test_motion_info_of_other_formats():
    from motionlang.formats.asf_amc import read_asf_amc
    amc = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    info = motion_info(amc)
    assert info["unit"] == "1/0.45 inch" and 1.6 < info["stature_m"] < 1.9


def test_binary_data_is_named_not_echoed(tmp_path):
    """Random bytes in a .bvh: the error says it is not text, without printing the bytes."""
    path = tmp_path / "noise.bvh"
    path.write_bytes(bytes(np.random.default_rng(0).integers(0, 256, 3000, dtype=np.uint8)))
    with pytest.raises(MotionFormatError, match="binary data") as info:
        read_bvh(path)
    assert "\ufffd" not in str(info.value) and all(c.isprintable() for c in str(info.value))


def test_one_odd_byte_in_a_text_file_is_quoted_not_called_binary(tmp_path):
    path = tmp_path / "latin1.bvh"
    path.write_bytes(b"HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 1\xe9\n")
    with pytest.raises(MotionFormatError) as info:
        read_bvh(path)
    assert "binary" not in str(info.value) and "malformed number" in str(info.value)

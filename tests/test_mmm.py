"""KIT MMM XML: the model facts against the original XML, the real motion 00001, writing,
and every kind of bad input."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from helpers.data import shared_file
from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.formats.mmm import MMM_DOF_ORDER, mmm_skeleton, read_mmm, write_mmm
from motionlang.formats.mmm_model import mmm_height, mmm_kinematics
from motionlang.kinematics import Motion


# ------------------------------------------------------------------ model facts
def _simox_nodes(path):
    """Independent parse of the Simox XML: name -> dict of the facts we keep."""
    root = ET.parse(path).getroot()
    out = {}
    for node in root.findall("RobotNode"):
        d = {"children": [c.get("name") for c in node.findall("Child")]}
        m = node.find("Transform/Matrix4x4")
        if m is not None:
            d["matrix"] = np.array([[float(m.find(f"row{i}").get(f"c{j}")) for j in range(1, 5)]
                                    for i in range(1, 5)])
        j = node.find("Joint")
        d["type"] = j.get("type") if j is not None else "fixed"
        if j is not None:
            ax = j.find("axis") if d["type"] == "revolute" else j.find("translationdirection")
            if ax is not None:
                d["axis"] = [float(ax.get(c)) for c in "xyz"]
            lim = j.find("limits")
            if lim is not None:
                d["limits"] = [float(lim.get("lo")), float(lim.get("hi"))]
        out[node.get("name")] = d
    return root.get("RootNode"), out


def test_project_copy_matches_the_reference_model():
    root, xml_nodes = _simox_nodes(shared_file("kitml/mmm_model.xml"))
    facts = mmm_kinematics()
    assert facts["root"] == root
    ours = {n["name"]: n for n in facts["nodes"]}
    # every body node is present (fingers are left out on purpose)
    body = {n for n in xml_nodes if "Finger" not in n}
    assert set(ours) == body
    for name, node in ours.items():
        ref = xml_nodes[name]
        assert node["type"] == ref["type"], name
        assert (node["parent"] is None) == (name == root)
        if node["parent"] is not None:
            assert name in xml_nodes[node["parent"]]["children"], name
        M = ref.get("matrix", np.eye(4))
        assert np.allclose(node.get("translation", [0, 0, 0]), M[:3, 3]), name
        assert np.allclose(node.get("rotation", np.eye(3)), M[:3, :3]), name
        assert np.allclose(M[3], [0, 0, 0, 1])
        if "axis" in ref:
            assert np.allclose(node["axis"], ref["axis"]), name
        if "limits" in ref:
            assert np.allclose(node["limits"], ref["limits"]), name
        if node["type"] == "prismatic" and "translation" in node:
            # the translation only gives the direction; it agrees with the joint's
            t = np.asarray(node["translation"], float)
            assert np.allclose(t / np.linalg.norm(t), node["axis"]), name
    # every recorded DOF is a revolute node of the model
    assert all(ours[n]["type"] == "revolute" for n in MMM_DOF_ORDER)


def test_segment_lengths_agree_with_the_models_own_markers():
    """Why the prismatic limits, not the transforms, are the segment lengths: with them the
    model's motion-capture markers sit where Winter's anthropometry puts the landmarks."""
    xml = ET.parse(shared_file("kitml/mmm_model.xml")).getroot()
    sk = mmm_skeleton(1.0)
    rot, pos = Motion(sk, 100.0, [[0, 0, 0.530]], np.zeros((1, 3)),
                      np.zeros((1, 44))).global_transforms()
    markers = {}
    for node in xml.findall("RobotNode"):
        if node.get("name") not in sk:
            continue
        j = sk.index(node.get("name"))
        for sensor in node.findall("Sensor"):
            m = sensor.find("Transform/Matrix4x4")
            t = np.array([float(m.find(f"row{i}").get("c4")) for i in (1, 2, 3)]) / 1000.0
            markers[sensor.get("name")] = pos[0, j] + rot[0, j] @ t
    z = {k: v[2] for k, v in markers.items()}
    assert abs(z["MARKER_LSHO"] - 0.818) < 0.01 and abs(z["MARKER_RSHO"] - 0.818) < 0.01
    assert 0.10 < -markers["MARKER_LSHO"][0] < 0.14  # half the biacromial width
    assert 0.92 < z["MARKER_LFHD"] < 1.0 and 0.80 < z["MARKER_C7"] < 0.86
    assert abs(z["MARKER_LKNE"] - 0.285) < 0.01


def test_skeleton_structure_and_scale():
    sk = mmm_skeleton(1.0)
    assert sk.ndof == 44 and sorted(sk.dof_names) == sorted(MMM_DOF_ORDER)
    assert sk.name == "mmm" and sk.file_unit == 0.001
    assert abs(mmm_height(mmm_skeleton(1.82)) - 1.82) < 1e-12
    # zero pose of the 1 m model: head top at 1.000, soles at 0 (Winter proportions)
    m = Motion(sk, 100.0, [[0, 0, 0.530]], np.zeros((1, 3)), np.zeros((1, 44)))
    p = m.positions()[0]
    assert abs(p[sk.index("HeadSegment_joint"), 1] - 1.0) < 1e-9
    assert abs(p[sk.index("LeftFootHeight_joint"), 1]) < 1e-9
    # left is -X in the source frame and +X canonical; the toes point forward (+Z)
    assert p[sk.index("LHsegment_joint"), 0] > 0 > p[sk.index("RHsegment_joint"), 0]
    assert p[sk.index("LFx_joint"), 2] > p[sk.index("LAx_joint"), 2] + 0.03
    # sizes scale linearly with height
    assert np.allclose(mmm_skeleton(1.8).offsets, 1.8 * sk.offsets)
    assert ("LKx_joint", "RKx_joint") in sk.pairs
    with pytest.raises(SkeletonError):
        mmm_skeleton(0.0)


def test_root_rotation_is_simox_rpy():
    """Simox ``rpy2eigen4f(r, p, y)``: m20 = -sin p, m21 = cos p sin r, m10 = sin y cos p."""
    from motionlang.kinematics.rotations import chain

    sk = mmm_skeleton(1.0)
    r, p, y = 0.3, -0.2, 1.1
    R = chain(sk.root_axes, np.array([y, p, r]))  # Motion.root_rotation = (yaw, pitch, roll)
    assert np.isclose(R[2, 0], -np.sin(p)) and np.isclose(R[2, 1], np.cos(p) * np.sin(r))
    assert np.isclose(R[1, 0], np.sin(y) * np.cos(p)) and np.isclose(R[0, 0], np.cos(y) * np.cos(p))
    assert np.isclose(R[2, 2], np.cos(p) * np.cos(r))


def test_knee_flexion_moves_foot_backwards():
    sk = mmm_skeleton(1.0)
    a = np.zeros((1, 44))
    a[0, sk.dof_names.index("LKx_joint")] = -np.pi / 2  # the model's knee limits are [-2.27, 0]
    p = Motion(sk, 100.0, [[0, 0, 0.530]], np.zeros((1, 3)), a).positions()[0]
    ankle, knee = p[sk.index("LAsegment_joint")], p[sk.index("LKsegment_joint")]
    assert np.allclose(ankle - knee, [0, 0, -0.246], atol=1e-9)


def test_mirror_swaps_sides_and_twice_is_identity():
    rng = np.random.default_rng(0)
    sk = mmm_skeleton(1.7)
    m = Motion(sk, 100.0, rng.normal(size=(5, 3)), rng.uniform(-0.3, 0.3, (5, 3)),
               rng.uniform(-0.5, 0.5, (5, 44)))
    mm = m.mirror()
    p, q = m.positions(), mm.positions()
    S = sk.world @ sk.mirror @ sk.world.T
    for left, right in sk.pairs:
        # the model itself is symmetric except for the ball of the foot: both LMrot and
        # RMrot sit at x = +0.6 mm (of a 1 m subject), so they mirror to within ~1.2 mm
        tol = 1.3e-3 * 1.7 if left in ("LMrot_joint", "LFx_joint") else 1e-9
        assert np.allclose(q[:, sk.index(left)], p[:, sk.index(right)] @ S.T, atol=tol), left
    assert np.allclose(mm.mirror().joint_angles, m.joint_angles)


# ------------------------------------------------------------------ the real motion
@pytest.fixture(scope="module")
def kit00001():
    return read_mmm(shared_file("kitml/00001_mmm.xml"))


def test_real_motion_shape_and_meta(kit00001):
    m = kit00001
    assert m.n_frames == 378 and m.fps == 100.0 and m.joint_angles.shape == (378, 44)
    assert m.meta["height"] == 1.82 and m.meta["mass"] == 100.0
    assert m.source_format == "mmm"
    # first frame values straight from the file (RootPosition mm, RootRotation r p y)
    assert np.allclose(m.root_translation[0], [1.14297, -0.252854, 0.973526])
    assert np.allclose(m.root_rotation[0], [1.64312, -0.0238353, -0.0735726])
    assert np.isclose(m.angle("BLNx_joint")[0], -0.612953)
    assert np.isclose(m.angle("RMrot_joint")[0], -0.261799)


def test_real_motion_is_a_plausible_walker(kit00001):
    m = kit00001
    sk = m.skeleton
    P = m.positions()
    top = P[:, sk.index("HeadSegment_joint"), 1]
    assert 1.6 < top.max() < 2.0 and 1.6 < np.median(top) < 2.0
    feet = [sk.index(n) for n in ("LeftFootHeight_joint", "RightFootHeight_joint",
                                  "LFx_joint", "RFx_joint")]
    lowest = P[:, feet, 1].min(axis=1)
    assert np.all(np.abs(lowest) < 0.05)  # a foot on the floor in every frame
    assert np.all(P[:, :, 1] > -0.05)  # nothing below the floor
    travel = P[-1, 0] - P[0, 0]
    # the subject stands ~2 s, then walks about 1.4 m (in this recording)
    assert 1.1 < np.hypot(travel[0], travel[2]) < 1.8 and abs(travel[1]) < 0.1
    # walking forwards: the travel direction agrees with the facing direction (up x left)
    left = P[-1, sk.index("LHsegment_joint")] - P[-1, sk.index("RHsegment_joint")]
    facing = np.cross(left, [0.0, 1.0, 0.0])
    assert np.dot(facing, travel) / np.linalg.norm(facing) / np.linalg.norm(travel) > 0.9
    # knees never hyperextend in the model's limits, and they bend while walking
    knee = m.angle("LKx_joint")
    assert knee.max() <= 1e-3 and knee.min() < -0.6


# ------------------------------------------------------------------ writing
def test_round_trip_real(kit00001, tmp_path):
    out = tmp_path / "copy.xml"
    write_mmm(kit00001, out)
    back = read_mmm(out)
    assert back.n_frames == 378 and back.fps == 100.0
    assert back.meta["height"] == 1.82 and back.meta["mass"] == 100.0
    for a, b in ((kit00001.root_translation, back.root_translation),
                 (kit00001.root_rotation, back.root_rotation),
                 (kit00001.joint_angles, back.joint_angles)):
        assert np.allclose(a, b, rtol=1e-5, atol=1e-6)
    write_mmm(back, tmp_path / "again.xml")  # printed values are a fixed point
    assert (tmp_path / "again.xml").read_text() == out.read_text()


def test_round_trip_random(tmp_path):
    rng = np.random.default_rng(1)
    sk = mmm_skeleton(1.64)
    m = Motion(sk, 25.0, rng.normal(size=(7, 3)), rng.uniform(-3, 3, (7, 3)),
               rng.uniform(-2, 2, (7, 44)), meta={"mass": 61.5, "subject": "a<b & 'c'"})
    write_mmm(m, tmp_path / "r.xml")
    back = read_mmm(tmp_path / "r.xml")
    assert back.fps == 25.0 and back.meta["height"] == 1.64 and back.meta["mass"] == 61.5
    assert back.meta["subject"] == "a<b & 'c'"
    assert np.allclose(back.joint_angles, m.joint_angles, rtol=1e-5, atol=1e-5)
    assert np.allclose(back.root_rotation, m.root_rotation, rtol=1e-5, atol=1e-5)
    assert np.allclose(back.root_translation, m.root_translation, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("fps", [30.0, 29.97, 12.5, 120.0])
def test_frame_rate_survives_writing(tmp_path, fps):
    sk = mmm_skeleton(1.7)
    m = Motion(sk, fps, np.zeros((50, 3)), np.zeros((50, 3)), np.zeros((50, 44)))
    write_mmm(m, tmp_path / "f.xml")
    assert read_mmm(tmp_path / "f.xml").fps == pytest.approx(fps, rel=1e-6)


def test_write_refuses_other_skeletons(tiny_motion, tmp_path):
    with pytest.raises(SkeletonError):
        write_mmm(tiny_motion, tmp_path / "x.xml")
    assert not (tmp_path / "x.xml").exists()


# ------------------------------------------------------------------ bad input
HEADER = """<?xml version='1.0'?>
<MMM>
  <Motion name='t'>
    <ModelProcessorConfig type='Winter'><Height>1.7</Height></ModelProcessorConfig>
    <JointOrder>
      <Joint name='LKx_joint'/>
      <Joint name='RKx_joint'/>
    </JointOrder>
    <MotionFrames>
"""
FRAME = """      <MotionFrame>
        <Timestep>{t}</Timestep>
        <RootPosition>0 0 900</RootPosition>
        <RootRotation>0 0 0</RootRotation>
        <JointPosition>{v}</JointPosition>
      </MotionFrame>
"""
FOOTER = "    </MotionFrames>\n  </Motion>\n</MMM>\n"


def _doc(values=("-0.1 -0.2", "-0.3 -0.4", "-0.5 -0.6"), header=HEADER):
    return header + "".join(FRAME.format(t=i * 0.01, v=v) for i, v in enumerate(values)) + FOOTER


def test_small_handwritten_file(tmp_path):
    p = tmp_path / "ok.xml"
    p.write_text(_doc())
    m = read_mmm(p)
    assert m.n_frames == 3 and m.fps == 100.0 and m.meta["mass"] is None
    assert np.allclose(m.angle("RKx_joint"), [-0.2, -0.4, -0.6])
    assert np.allclose(m.angle("LHx_joint"), 0.0)  # DOFs not listed stay 0
    assert np.allclose(m.root_translation[:, 2], 0.9)


def _error(tmp_path, text) -> MotionFormatError:
    p = tmp_path / "bad.xml"
    p.write_text(text)
    with pytest.raises(MotionFormatError) as info:
        read_mmm(p)
    assert "bad.xml" in str(info.value)
    return info.value


def _line_of(text, needle):
    return text[:text.index(needle)].count("\n") + 1


def test_truncated_xml(tmp_path):
    err = _error(tmp_path, _doc()[:-40])
    assert err.line is not None and "XML" in err.reason


def test_malformed_number(tmp_path):
    text = _doc(("-0.1 -0.2", "-0.3 -0.4x", "-0.5 -0.6"))
    err = _error(tmp_path, text)
    assert err.frame == 1 and "-0.4x" in err.reason
    assert err.line == _line_of(text, "<MotionFrame>\n        <Timestep>0.01")


def test_wrong_value_count(tmp_path):
    err = _error(tmp_path, _doc(("-0.1 -0.2", "-0.3 -0.4", "-0.5")))
    assert err.frame == 2 and "1 values, expected 2" in err.reason and err.line is not None


def test_nan_frame(tmp_path):
    err = _error(tmp_path, _doc(("nan -0.2", "-0.3 -0.4", "-0.5 -0.6")))
    assert err.frame == 0 and "NaN" in err.reason


def test_unknown_joint(tmp_path):
    err = _error(tmp_path, _doc(header=HEADER.replace("RKx_joint", "RKnee_joint")))
    assert "RKnee_joint" in err.reason


def test_zero_frames(tmp_path):
    err = _error(tmp_path, _doc(values=()))
    assert "no frames" in err.reason


def test_missing_joint_order(tmp_path):
    start, end = HEADER.index("<JointOrder>"), HEADER.index("</JointOrder>")
    err = _error(tmp_path, _doc(header=HEADER[:start] + HEADER[end + len("</JointOrder>"):]))
    assert "JointOrder" in err.reason


def test_missing_root_position_and_bad_height(tmp_path):
    err = _error(tmp_path, _doc().replace("<RootPosition>0 0 900</RootPosition>", "", 1))
    assert err.frame == 0 and "RootPosition" in err.reason
    err = _error(tmp_path, _doc(header=HEADER.replace("1.7", "tall")))
    assert "Height" in err.reason


def test_object_motion_before_the_human(tmp_path):
    obj = ("  <Motion name='cup'><Model><File>cup.xml</File></Model><JointOrder>"
           "<Joint name='lid_joint'/></JointOrder></Motion>\n")
    text = _doc().replace("  <Motion name='t'>", obj + "  <Motion name='t'>\n"
                          "    <Model><File>mmm.xml</File></Model>", 1)
    p = tmp_path / "two.xml"
    p.write_text(text)
    m = read_mmm(p)
    assert m.meta["subject"] == "t" and np.allclose(m.angle("LKx_joint"), [-0.1, -0.3, -0.5])


def test_missing_file(tmp_path):
    with pytest.raises(MotionFormatError):
        read_mmm(tmp_path / "nope.xml")


@pytest.mark.parametrize("decl, words", [
    ("encoding='utf-32'", "cannot read the declared encoding"),
    ("encoding='klingon'", "cannot read the declared encoding"),
    ("encoding='utf-16'", "encoding"),  # declared, but the bytes are not UTF-16
])
def test_unreadable_encodings(tmp_path, decl, words):
    err = _error(tmp_path, _doc().replace("<?xml version='1.0'?>", f"<?xml version='1.0' {decl}?>"))
    assert words in err.reason and "\n" not in str(err)


def test_a_real_utf16_file_reads(tmp_path):
    p = tmp_path / "u16.xml"
    p.write_bytes(_doc().replace("<?xml version='1.0'?>",
                                 "<?xml version='1.0' encoding='utf-16'?>").encode("utf-16"))
    assert read_mmm(p).n_frames == 3


LAUGHS = ('<!DOCTYPE MMM [<!ENTITY a "aaaaaaaaaa">' + "".join(
    f'<!ENTITY {chr(98 + i)} "{("&" + chr(97 + i) + ";") * 10}">' for i in range(8)) + "]>")


@pytest.mark.parametrize("dtd, use", [
    (LAUGHS, "&i;"),                                               # billion laughs
    ('<!DOCTYPE MMM [<!ENTITY e SYSTEM "file:///etc/passwd">]>', "&e;"),  # external entity
    ('<!DOCTYPE MMM [<!ENTITY % p SYSTEM "http://127.0.0.1:9/x.dtd"> %p;]>', "0"),
    ('<!DOCTYPE MMM SYSTEM "http://127.0.0.1:9/mmm.dtd">', "0"),
    ('<!DOCTYPE MMM [<!ENTITY e "-0.3">]>', "&e;"),                # even a harmless one
])
def test_dtds_and_entities_are_refused(tmp_path, dtd, use):
    text = _doc().replace("<?xml version='1.0'?>", "<?xml version='1.0'?>" + dtd, 1)
    err = _error(tmp_path, text.replace("-0.3", use, 1))
    assert "document type declaration" in err.reason and err.line is None


def test_frame_limit(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_MAX_FRAMES", "2")
    err = _error(tmp_path, _doc())
    assert "frame count 3 exceeds the limit of 2" in err.reason
    assert "MOTIONLANG_MAX_FRAMES" in err.reason

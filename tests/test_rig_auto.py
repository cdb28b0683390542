"""Rigs no built-in table fits are mapped from their tree, rest pose and names
(``features.rig_auto``): the map is the one a person would write, the body it gives stands
the right way round, every command reads the rigs without ``--joint-map``, and a rig whose
names contradict its rest pose is an error that says so. The automatic map also agrees with
every built-in table on that table's own standing fixture."""
import json
import re
import tarfile

import numpy as np
import pytest

from helpers import rigs as rf
from helpers.auto_rigs import AUTO_RIGS, EXPECTED, mirrored
from helpers.data import shared_file
from motionlang.cli.main import main
from motionlang.errors import SkeletonError
from motionlang.features.joint_map import KIT21_NAMES, match_rig, positions21
from motionlang.features.rig_auto import auto_map, name_side
from motionlang.formats import read_motion
from motionlang.kinematics import Motion

I = {n: i for i, n in enumerate(KIT21_NAMES)}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("auto_rigs")
    return {name: rf.write(rig, folder, T=24) for name, rig in AUTO_RIGS.items()}


def _rest(motion):
    sk = motion.skeleton
    return Motion(sk, 10.0, np.zeros((1, 3)), np.zeros((1, len(sk.root_axes))),
                  np.zeros((1, sk.ndof)))


def _stands_right(p):
    """A rest-pose body (21, 3) in the fixtures' axes (x = the subject's left, y up, z
    forward), arms out: fails for a map with sides swapped, hands, feet or trunk confused."""
    for s, sign in (("L", 1), ("R", -1)):
        for j in ("S", "E", "W", "H", "K", "A", "F"):
            assert sign * p[I[s + j], 0] > 0.02, f"{s}{j} on the wrong side"
        assert p[I[s + "F"], 2] > p[I[s + "A"], 2]              # toes ahead of the ankle
        assert p[I[s + "H"], 1] > p[I[s + "K"], 1] > p[I[s + "A"], 1]
        assert sign * p[I[s + "W"], 0] > sign * p[I[s + "E"], 0] > sign * p[I[s + "S"], 0]
    feet = [I[n] for n in ("LA", "LF", "RA", "RF", "LMrot", "RMrot")]
    assert p[feet, 1].max() < np.delete(p[:, 1], feet).min()   # the feet lowest
    assert int(np.argmax(p[:, 1])) == I["BUN"]                    # the head highest
    assert p[I["root"], 1] < p[I["BP"], 1] < p[I["BT"], 1] < p[I["BLN"], 1]


@pytest.mark.parametrize("name", list(AUTO_RIGS))
def test_mapped_like_by_hand_and_stands_right(files, name):
    motion = read_motion(files[name])
    m = match_rig(motion.skeleton)
    assert m.name == "auto" and m.how is not None
    assert all(conf >= 0.5 for _, conf in m.how.values())
    hand = positions21(motion, joint_map=EXPECTED[name])
    assert np.allclose(positions21(motion), hand, atol=1e-9)
    _stands_right(positions21(_rest(motion))[0])


@pytest.mark.parametrize("name", list(AUTO_RIGS))
def test_every_command_reads_them_without_a_map(files, name, tmp_path, capsys):
    path = files[name]
    assert main(["rig", "show", str(path)]) == 0
    out = capsys.readouterr().out
    assert "map      auto: automatic" in out
    rows = {ln.split()[0]: ln.split() for ln in out.splitlines() if " <- " in ln
            and not ln.lstrip().startswith("body")}
    assert list(rows) == list(KIT21_NAMES)
    assert all(r[1] in ("name", "topology") and 0.5 <= float(r[2]) <= 1 for r in rows.values())
    expected = EXPECTED[name]["joints"]
    assert rows["LW"][-1] == expected["LW"] and rows["RH"][-1] == expected["RH"]
    assert main(["rig", "show", str(path), "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["map"] == "auto" and shown["how"]["LK"][0] == "name"
    assert main(["info", str(path)]) == 0
    capsys.readouterr()
    for out in ("x.bvh", "x.png"):
        verb = "render" if out.endswith(".png") else "convert"
        assert main([verb, str(path), str(tmp_path / out)]) == 0
        assert (tmp_path / out).stat().st_size > 0


def test_describe_reads_them_without_a_map(files, capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    for path in files.values():
        assert main(["describe", str(path), "-w", "1"]) == 0
        # the model's sentence, or the grounded one where the model contradicts the body
        assert re.match(r"1\. +(log P =|grounded)", capsys.readouterr().out)


@pytest.mark.parametrize("name", list(AUTO_RIGS))
def test_names_against_the_rest_pose_is_an_error_with_the_way_out(name, tmp_path, capsys):
    path = rf.write(mirrored(AUTO_RIGS[name]), tmp_path, T=4)
    with pytest.raises(SkeletonError) as err:
        positions21(read_motion(path))
    msg = str(err.value)
    assert "automatic map unsure: arms: the names say" in msg
    assert "but the rest pose puts it on the left" in msg
    assert msg.endswith("motionlang rig template FILE > map.json") and "--joint-map" in msg
    assert main(["rig", "show", str(path)]) == 2
    assert "automatic map unsure" in capsys.readouterr().err


def test_no_side_names_is_doubted_and_a_map_still_works(tmp_path):
    """bone_NN names: the rest pose alone would say left and right; a mirrored export
    would swap them unseen, so it is an error naming that doubt."""
    rig = AUTO_RIGS["biovision"]
    text = rf.bvh_text(rig, T=4)
    names = [n for n in (ln.split()[1] for ln in text.splitlines()
                         if ln.strip().startswith(("ROOT", "JOINT")))]
    for i, n in sorted(enumerate(names), key=lambda kv: -len(kv[1])):
        text = text.replace(f" {n}\n", f" bone_{i:02d}\n")
    (tmp_path / "bones.bvh").write_text(text)
    motion = read_motion(tmp_path / "bones.bvh")
    auto = auto_map(motion.skeleton)
    assert not auto.confident and auto.joints
    assert any("no joint name says which side" in d for d in auto.doubts)
    with pytest.raises(SkeletonError, match="left and right from the rest pose alone"):
        positions21(motion)


def test_side_names_of_several_conventions():
    keys = {"lfemur", "rfemur", "thigh.l", "thigh.r", "cc_base_l_thigh", "cc_base_r_thigh",
            "lowerback", "hand_l", "hand_r"}
    assert [name_side(n, keys) for n in ("lfemur", "rfemur", "thigh.L", "thigh.R",
                                         "CC_Base_L_Thigh", "mHipRight", "LeftUpLeg",
                                         "hand_L", "lowerback", "Head")] == \
        [1, -1, 1, -1, 1, -1, 1, 1, 0, 0]


@pytest.mark.parametrize("name", [n for n, r in rf.RIGS.items() if not r.along_x])
def test_agrees_with_every_standing_table(name, tmp_path):
    """On each built-in map's own fixture the automatic map gives the same body."""
    motion = read_motion(rf.write(rf.RIGS[name], tmp_path, T=4))
    table = match_rig(motion.skeleton)
    assert table.name == name and set(table.how.values()) == {("table", 1.0)}
    auto = auto_map(motion.skeleton)
    assert auto.confident, auto.doubts
    p = motion.positions()
    joints = {k: f.spec for k, f in auto.joints.items()}
    if name == "cc":
        # the table reads CC's back at Spine01 and Spine02: its Waist and Spine01 sit low
        # and forward, where no other rig's lumbar and thorax joints are (a trunk retargeted
        # from them leaned 12 degrees); the automatic map takes a spine's first two joints
        assert (joints["BP"], joints["BT"]) == ("CC_Base_Waist", "CC_Base_Spine01")
        joints.update(BP="CC_Base_Spine01", BT="CC_Base_Spine02")
    auto_w = positions21(motion, joint_map={"name": "auto", "joints": joints})
    assert np.allclose(auto_w, np.einsum("kj,tjc->tkc", table.weights, p), atol=1e-6)


def test_real_makehuman_file(tmp_path, capsys):
    archive = shared_file("cmu_dev/cmu-dev.tar.xz")
    with tarfile.open(archive, "r:xz") as tar:
        data = tar.extractfile("cmu-dev/makehuman/05_01.bvh").read()
    path = tmp_path / "05_01.bvh"
    path.write_bytes(data)
    motion = read_motion(path)
    assert len(motion.skeleton.names) > 150
    m = match_rig(motion.skeleton)
    assert m.name == "auto" and min(c for _, c in m.how.values()) >= 0.8
    assert m.sources["LW"] == "lhand" and m.sources["RK"] == "rknee"
    assert m.sources["BUN"] == "head" and m.sources["LF"] == "toe3-1.l"
    p = positions21(motion[:1])[0]
    assert p[I["BUN"], 1] > p[I["BLN"], 1] > p[I["root"], 1] > p[I["LK"], 1] > p[I["LA"], 1]
    assert main(["rig", "show", str(path)]) == 0
    assert "map      auto" in capsys.readouterr().out


def test_an_iclone_take_retargeted_onto_another_rig_stands_as_upright(tmp_path):
    """CMU 05_01 as iClone's CC rig has it, moved onto the Second Life rig of the same
    trial: the trunk (pelvis to neck) leans as the source's does, within 1 degree (it leaned
    12 degrees more while the CC map read the back at its low, forward Waist and Spine01)."""
    import motionlang as ml
    from motionlang.analysis.body import Body
    with tarfile.open(shared_file("cmu_dev/cmu-dev.tar.xz"), "r:xz") as tar:
        for rig in ("iclone", "secondlife"):
            (tmp_path / f"{rig}.bvh").write_bytes(
                tar.extractfile(f"cmu-dev/{rig}/05_01.bvh").read())
    src = read_motion(tmp_path / "iclone.bvh")
    copy = ml.retarget(src, tmp_path / "secondlife.bvh")

    def lean(m) -> float:
        return float(np.median(Body.from_positions(positions21(m), m.fps).trunk_tilt))
    assert abs(lean(copy) - lean(src)) < 1.0

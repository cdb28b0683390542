"""read_motion / write_motion / motion_info: choosing readers and writers by extension,
finding the ASF of an AMC, and clear errors."""
import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import HAND, TINY_ASF, tiny_amc
from motionlang.errors import MotionFormatError
from motionlang.formats import find_asf, motion_info, read_motion, write_motion

FRAME = ([0, 0, 0, 0, 0, 0], [1, 2, 3], 4, 5)


def test_amc_with_sibling_subject_asf(tmp_path):
    (tmp_path / "07.asf").write_text(TINY_ASF)
    (tmp_path / "other.asf").write_text(TINY_ASF.replace("name chest", "name chest2")
                                        .replace("root chest", "root chest2")
                                        .replace("chest larm", "chest2 larm"))
    (tmp_path / "07_03.amc").write_text(tiny_amc([FRAME] * 4))
    assert find_asf(tmp_path / "07_03.amc") == tmp_path / "07.asf"
    m = read_motion(tmp_path / "07_03.amc")
    assert m.n_frames == 4 and m.fps == 120.0 and m.skeleton.name == "cmu:07"
    m = read_motion(tmp_path / "07_03.amc", skeleton=tmp_path / "07.asf", fps=30)
    assert m.fps == 30.0
    same = read_motion(tmp_path / "07_03.amc", skeleton=m.skeleton)
    assert same.skeleton is m.skeleton


def test_amc_with_the_only_asf_in_folder(tmp_path):
    (tmp_path / "skeleton.asf").write_text(TINY_ASF)
    (tmp_path / "walk.amc").write_text(tiny_amc([FRAME] * 2))
    assert read_motion(tmp_path / "walk.amc").skeleton.name == "cmu:skeleton"
    (tmp_path / "second.asf").write_text(TINY_ASF)
    with pytest.raises(MotionFormatError, match="cannot choose the ASF"):
        read_motion(tmp_path / "walk.amc")


def test_amc_without_asf(tmp_path):
    (tmp_path / "walk.amc").write_text(tiny_amc([FRAME]))
    with pytest.raises(MotionFormatError, match="no walk.asf"):
        read_motion(tmp_path / "walk.amc")


def test_real_amc_and_info():
    m = read_motion(shared_file("cmu49/49_20.amc"))
    info = motion_info(m)
    assert info["frames"] == 898 and info["fps"] == 120.0
    assert info["duration_s"] == pytest.approx(898 / 120)
    # 28 bones carry rotations; 38 nodes with the root, hip joints and end sites
    assert info["joints"] == len(info["joint_names"]) == 28 and info["dofs"] == 56
    assert info["nodes"] == len(info["node_names"]) == 38 and "root" in info["node_names"]
    assert info["source_format"] == "amc" and info["name"] == "49_20"
    assert "lfemur" in info["joint_names"] and "lhipjoint" not in info["joint_names"]


def test_mit_mat_by_sequence():
    path = shared_file("mit/motion.mat")
    first, third = read_motion(path), read_motion(path, sequence=3)
    assert (first.n_frames, third.n_frames) == (438, 3128) and first.fps == 30.0
    assert first.source_format == "mit" and motion_info(third)["frames"] == 3128
    with pytest.raises(MotionFormatError, match="no sequence 4.*holds 3"):
        read_motion(path, sequence=4)


def test_bvh_and_resampling(tmp_path):
    (tmp_path / "h.BVH").write_text(HAND)
    m = read_motion(tmp_path / "h.BVH")
    assert m.source_format == "bvh" and m.n_frames == 3
    half = read_motion(tmp_path / "h.BVH", fps=15)
    assert half.fps == 15 and half.n_frames == 2
    assert np.allclose(half.joint_angles[1], m.joint_angles[2])


def test_mmm_xml():
    pytest.importorskip("motionlang.formats.mmm")
    m = read_motion(shared_file("kitml/00001_mmm.xml"))
    assert m.source_format == "mmm" and m.n_frames == 378


def test_write_motion_by_extension(tmp_path, tiny_motion):
    (tmp_path / "07.asf").write_text(TINY_ASF)
    (tmp_path / "07_01.amc").write_text(tiny_amc([FRAME] * 3))
    m = read_motion(tmp_path / "07_01.amc")
    write_motion(m, tmp_path / "07_02.amc")
    assert np.allclose(read_motion(tmp_path / "07_02.amc").joint_angles, m.joint_angles)
    write_motion(tiny_motion, tmp_path / "tiny.bvh")
    back = read_motion(tmp_path / "tiny.bvh")
    # DOF-free leaves become End Sites (named after their parent); the leaf "Spine" has
    # DOFs, so the writer gives it an End Site of its own
    assert back.skeleton.names == ["Hips", "LeftUpLeg", "LeftLeg", "LeftLeg_end", "RightUpLeg",
                                   "RightLeg", "RightLeg_end", "Spine", "Spine_end"]
    assert np.allclose(back.positions()[:, :-1], tiny_motion.positions(), atol=1e-6)
    with pytest.raises(MotionFormatError, match="MMM"):
        write_motion(tiny_motion, tmp_path / "tiny.xml")
    with pytest.raises(MotionFormatError, match="not an ASF"):
        write_motion(tiny_motion, tmp_path / "tiny.amc")
    with pytest.raises(MotionFormatError, match="cannot write"):
        write_motion(tiny_motion, tmp_path / "tiny.fbx")
    assert not (tmp_path / "tiny.amc").exists() and not (tmp_path / "tiny.fbx").exists()


@pytest.mark.parametrize("name,words", [("a.fbx", "unknown motion file extension"),
                                        ("noext", "unknown motion file extension"),
                                        ("gone.bvh", "not found"), ("gone.amc", "not found")])
def test_read_errors(tmp_path, name, words):
    if name == "a.fbx":
        (tmp_path / name).write_text("x")
    with pytest.raises(MotionFormatError, match=words):
        read_motion(tmp_path / name)

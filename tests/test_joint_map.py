import itertools

import numpy as np
import pytest

from helpers.data import shared_file
from helpers.mocap import tiny_skeleton
from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features.joint_map import (
    KIT21_NAMES,
    KIT21_PARENTS,
    bone_lengths21,
    kit21_weights,
    positions21,
)
from motionlang.formats.asf_amc import read_asf_amc
from motionlang.formats.mmm import read_mmm
from motionlang.formats.mmm_model import mmm_skeleton
from motionlang.kinematics import Joint, Motion, Skeleton

# bones whose segmentation differs between the MMM and CMU models (see test below)
TRUNK = {("BP", "root"), ("BT", "BP"), ("BLN", "BT"), ("BUN", "BLN")}


def _still(sk, n=1):
    return Motion(sk, 10.0, np.zeros((n, 3)), np.zeros((n, len(sk.root_axes))),
                  np.zeros((n, sk.ndof)))


def _stature(motion):
    """Vertical extent of the skeleton's zero pose (metres)."""
    y = _still(motion.skeleton).positions()[0, :, 1]
    return y.max() - y.min()


def test_layout_is_a_tree():
    assert len(KIT21_NAMES) == 21 and KIT21_PARENTS[0] == -1
    assert all(0 <= p < i for i, p in enumerate(KIT21_PARENTS) if i)


def test_mmm_map_picks_the_named_segments():
    sk = mmm_skeleton(1.8)
    rng = np.random.default_rng(1)
    m = Motion(sk, 100.0, rng.normal(size=(4, 3)), rng.uniform(-0.5, 0.5, (4, 3)),
               rng.uniform(-0.5, 0.5, (4, sk.ndof)))
    name, _ = kit21_weights(sk)
    assert name == "mmm"
    p21, p = positions21(m), m.positions()
    assert np.allclose(p21[:, KIT21_NAMES.index("LK")], p[:, sk.index("LKsegment_joint")])
    assert np.allclose(p21[:, KIT21_NAMES.index("RF")], p[:, sk.index("RFx_joint")])
    # standing still: the subject's left hip is on canonical +x, toes point forward (+z)
    q = positions21(_still(sk))[0]
    assert q[KIT21_NAMES.index("LH"), 0] > 0 > q[KIT21_NAMES.index("RH"), 0]
    assert q[KIT21_NAMES.index("LF"), 2] > q[KIT21_NAMES.index("LA"), 2]


def _bvh_skeleton(prefix, cmu_spine):
    """Minimal BVH-like skeleton with CMU-converted or Mixamo names."""
    spine = ["LowerBack", "Spine", "Spine1", "Neck", "Neck1", "Head"] if cmu_spine else \
        ["Spine", "Spine1", "Spine2", "Neck", "Head"]
    joints = [Joint(prefix + "Hips", -1, [0, 0, 0])]

    def add(name, parent, off):
        joints.append(Joint(prefix + name, [j.name for j in joints].index(prefix + parent),
                            off, axes=np.eye(3)[[2, 0, 1]]))
    prev = "Hips"
    for s in spine:
        add(s, prev, [0, 0.1, 0])
        prev = s
    for side, x in (("Left", 1), ("Right", -1)):
        add(f"{side}UpLeg", "Hips", [0.1 * x, -0.05, 0])
        add(f"{side}Leg", f"{side}UpLeg", [0, -0.45, 0])
        add(f"{side}Foot", f"{side}Leg", [0, -0.45, 0])
        add(f"{side}ToeBase", f"{side}Foot", [0, -0.05, 0.12])
        add(f"{side}Shoulder", spine[-3], [0.05 * x, 0.05, 0])
        add(f"{side}Arm", f"{side}Shoulder", [0.12 * x, 0, 0])
        add(f"{side}ForeArm", f"{side}Arm", [0.3 * x, 0, 0])
        add(f"{side}Hand", f"{side}ForeArm", [0.25 * x, 0, 0])
    return Skeleton(joints, name="bvh")


@pytest.mark.parametrize("prefix,cmu_spine,expect", [
    ("", True, "cmu-bvh"), ("mixamorig:", False, "mixamo"), ("", False, "bvh")])
def test_bvh_naming_schemes(prefix, cmu_spine, expect):
    sk = _bvh_skeleton(prefix, cmu_spine)
    name, W = kit21_weights(sk)
    assert name == expect
    assert np.allclose(W.sum(1), 1.0)  # every KIT joint is a convex combination
    p21, p = positions21(_still(sk)), _still(sk).positions()
    assert np.allclose(p21[0, KIT21_NAMES.index("LE")], p[0, sk.index(prefix + "LeftForeArm")])
    root = (p[0, sk.index(prefix + "LeftUpLeg")] + p[0, sk.index(prefix + "RightUpLeg")]) / 2
    assert np.allclose(p21[0, 0], root)
    bus = "Head"
    assert np.allclose(p21[0, KIT21_NAMES.index("BUN")], p[0, sk.index(prefix + bus)])


def test_unmappable_skeleton_names_missing_joints():
    with pytest.raises(SkeletonError, match="cannot be mapped.*LeftArm"):
        positions21(_still(tiny_skeleton()))
    with pytest.raises(SkeletonError, match="unknown joint map"):
        kit21_weights(tiny_skeleton(), "nope")


def test_cmu_and_kit_bone_lengths_agree_after_height_scaling():
    kit = read_mmm(shared_file("kitml/00001_mmm.xml"))
    cmu = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    lk = bone_lengths21(positions21(kit)) / _stature(kit)
    lc = bone_lengths21(positions21(cmu)) / _stature(cmu)
    assert abs(_stature(kit) - kit.meta["height"]) < 1e-6  # MMM zero pose stands its height
    bones = [(KIT21_NAMES[i], KIT21_NAMES[KIT21_PARENTS[i]]) for i in range(1, 21)]
    limbs = [k for k, b in enumerate(bones) if b not in TRUNK]
    # limb bones are rigid over a motion (synthetic mid-foot and root points included);
    # CMU trunk "bones" span several spine joints and bend a little
    assert np.allclose(lk.std(0), 0, atol=1e-6) and np.allclose(lc[:, limbs].std(0), 0, atol=1e-6)
    lk, lc = lk.mean(0, keepdims=True), lc.mean(0, keepdims=True)
    rel = lc[0] / lk[0] - 1.0
    worst = max(limbs, key=lambda k: abs(rel[k]))
    assert len(limbs) == 16
    assert abs(rel[worst]) < 0.20, f"worst limb bone {bones[worst]}: {rel[worst]:+.0%}"
    # The two models cut the trunk differently (MMM: lumbar 0.04 H, neck 0.03 H; CMU:
    # 0.07 H and 0.12 H), so segments differ; the whole root->head-base chain agrees.
    trunk = [k for k, b in enumerate(bones) if b in TRUNK]
    assert abs(lc[0, trunk].sum() / lk[0, trunk].sum() - 1.0) < 0.20


def test_no_choice_of_cmu_spine_nodes_matches_the_mmm_trunk():
    """Why the trunk is compared as a whole chain: over every choice of 5 points in order
    along CMU's spine (hip midpoint, lowerback .. head_end) for root, BP, BT, BLN, BUN, some
    trunk bone still differs from MMM's by more than 20 % (MMM's lumbar joint BP sits
    0.04 H above the hip line; CMU's nearest spine nodes sit at 0 and 0.066 H)."""
    kit = read_mmm(shared_file("kitml/00001_mmm.xml"))
    cmu = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    pk = positions21(_still(kit.skeleton))[0] / _stature(kit)
    kit_trunk = pk[[KIT21_NAMES.index(n) for n in ("root", "BP", "BT", "BLN", "BUN")]]
    kit_len = np.linalg.norm(np.diff(kit_trunk, axis=0), axis=1)
    sk = cmu.skeleton
    pc = _still(sk).positions()[0] / _stature(cmu)
    spine = [(pc[sk.index("lfemur")] + pc[sk.index("rfemur")]) / 2] + [
        pc[sk.index(n)] for n in ("lowerback", "upperback", "thorax", "lowerneck",
                                  "upperneck", "head", "head_end")]
    worst = []
    for combo in itertools.combinations(range(len(spine)), 5):
        lens = np.linalg.norm(np.diff(np.array([spine[i] for i in combo]), axis=0), axis=1)
        worst.append(np.abs(lens / kit_len - 1).max())
    assert min(worst) > 0.20
    assert pk[KIT21_NAMES.index("BP"), 1] - pk[0, 1] < 0.05  # BP close above the hip line


def test_cmu_through_bvh_maps_to_the_same_points(tmp_path):
    from motionlang.formats.bvh import read_bvh, write_bvh
    cmu = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))[:30]
    write_bvh(cmu, tmp_path / "35_01.bvh")
    back = read_bvh(tmp_path / "35_01.bvh")
    assert np.abs(positions21(back) - positions21(cmu)).max() < 1e-5


def test_uniform_bones_keeps_directions_and_scales_strides():
    from motionlang.features.body21 import leg_length21, uniform_bones21
    rng = np.random.default_rng(0)
    # a random posed body that walks 0.5 m along +z over 10 frames
    base = np.array(KIT21_PARENTS)
    p = np.zeros((10, 21, 3))
    offs = rng.normal(0, 0.2, (21, 3))
    for t in range(10):
        p[t, 0] = (0.0, 1.0, 0.05 * t)
        for j in range(1, 21):
            p[t, j] = p[t, base[j]] + offs[j] + rng.normal(0, 0.02, 3)
    want = rng.uniform(0.05, 0.5, 20)
    q = uniform_bones21(p, want)
    assert np.allclose(bone_lengths21(q), want)
    for j in range(1, 21):
        d0, d1 = p[:, j] - p[:, base[j]], q[:, j] - q[:, base[j]]
        cos = (d0 * d1).sum(-1) / np.linalg.norm(d0, axis=-1) / np.linalg.norm(d1, axis=-1)
        assert np.allclose(cos, 1.0)
    ratio = leg_length21(want) / leg_length21(bone_lengths21(p))
    assert np.allclose(q[:, 0] - q[0, 0], (p[:, 0] - p[0, 0]) * ratio)
    assert np.allclose(uniform_bones21(p, np.median(bone_lengths21(p), axis=0))[:, 0], p[:, 0])
    with pytest.raises(MotionlangError, match="20 finite lengths"):
        uniform_bones21(p, want[:19])

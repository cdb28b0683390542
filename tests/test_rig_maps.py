"""One body for every rig: hand-written BVH fixtures (``tests/helpers/rigs.py``) in each
built-in map's naming, unit and axes choose that map, and their 21-joint body, normalised,
has KIT proportions, stands on the floor and faces +Z; user JSON maps and templates; the
error when no map fits; real KIT and CMU motions; MMM and CMU choices unchanged."""
import json

import numpy as np
import pytest

from helpers import rigs as rf
from helpers.auto_rigs import mirrored
from helpers.data import shared_file
from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features import PositionFeatures
from motionlang.features.body21 import body21, normalise21, stature21
from motionlang.features.joint_map import (
    JOINT_MAPS,
    KIT21_NAMES,
    KIT21_PARENTS,
    bone_lengths21,
    kit21_weights,
    load_joint_map,
    match_rig,
    positions21,
    positions21_from_smpl,
    template_map,
)
from motionlang.features.positions import facing_yaw, floor_height
from motionlang.features.rig_maps import SMPL_JOINT_NAMES
from motionlang.formats import read_motion
from motionlang.formats.asf_amc import read_asf_amc
from motionlang.formats.mmm import read_mmm
from motionlang.formats.mmm_model import mmm_skeleton
from motionlang.kinematics import Joint, Motion, Skeleton

I = {n: i for i, n in enumerate(KIT21_NAMES)}
BONES = [f"{KIT21_NAMES[i]}-{KIT21_NAMES[KIT21_PARENTS[i]]}" for i in range(1, 21)]
TRUNK = [BONES.index(b) for b in ("BP-root", "BT-BP", "BLN-BT", "BUN-BLN")]
LIMBS = [k for k in range(20) if k not in TRUNK]
# Facts of a rig that put a limb bone more than 25 % off MMM's, checked rather than hidden:
# Bandai Namco's shoulder joints are 10.3 cm from the midline (Shoulder 5.0 + UpperArm
# 5.3 cm) on a 1.56 m body; the DAZ-friendly figure's 11.5 cm (lCollar 2.7 + lShldr 8.8 cm)
# on 1.70 m; MMM's are 0.11 H from it.
KNOWN = {"bandai": {"LS-BLN", "RS-BLN"}, "cmu-bvh-daz": {"LS-BLN", "RS-BLN"}}


def _still(sk, n=1):
    return Motion(sk, 10.0, np.zeros((n, 3)), np.zeros((n, len(sk.root_axes))),
                  np.zeros((n, sk.ndof)))


KIT_BONES = bone_lengths21(positions21(_still(mmm_skeleton(1.0))))[0]  # per metre of stature


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rigs")
    return {name: rf.write(rig, folder) for name, rig in rf.RIGS.items()}


def _check_body(b, stature, known=frozenset(), sink=0.02, toes0=True):
    """Proportions, floor and facing of a normalised 21-joint walk (T, 21, 3)."""
    rel = bone_lengths21(b).mean(0) / (KIT_BONES * stature) - 1
    off = {BONES[k]: f"{rel[k]:+.0%}" for k in LIMBS if abs(rel[k]) > 0.25}
    assert set(off) == set(known), off
    assert all(abs(rel[BONES.index(k)]) < 0.40 for k in known)
    chain = bone_lengths21(b)[:, TRUNK].sum(1).mean() / (KIT_BONES[TRUNK].sum() * stature)
    assert abs(chain - 1) < 0.25, f"root-to-head-base chain {chain - 1:+.0%}"
    # on the floor: the lowest foot joint at y = 0, never below it by more than 2 cm;
    # standing: the head base at MMM's height over the floor (0.87 H) within 10 %
    assert abs(floor_height(b)) < 1e-9
    assert b[:, [I["LA"], I["LF"], I["RA"], I["RF"]], 1].min() > -sink
    assert abs(b[0, I["BUN"], 1] / (0.87 * stature) - 1) < 0.10
    # facing +Z: frame 0's root over the origin, heading 0, the subject's left on +x, toes
    # ahead of the ankles, and a walk goes forward
    assert np.allclose(b[0, 0, [0, 2]], 0, atol=1e-9) and abs(facing_yaw(b[:1])[0]) < 1e-9
    assert b[0, I["LH"], 0] > 0 > b[0, I["RH"], 0]
    if toes0:   # (a real take may start with a swinging foot pointing down and back)
        assert b[0, I["LF"], 2] > b[0, I["LA"], 2] and b[0, I["RF"], 2] > b[0, I["RA"], 2]


def test_every_built_in_map_has_a_fixture_and_every_table_is_complete():
    # mmm, cmu-asf and mit: real files; body21: motionlang's own output (test_real_rigs_cli);
    # deepmimic: its reader's own skeleton (test_deepmimic)
    assert set(rf.RIGS) == set(JOINT_MAPS) - {"mmm", "cmu-asf", "mit", "body21", "deepmimic"}
    for name, table in JOINT_MAPS.items():
        assert list(sorted(table)) == sorted(KIT21_NAMES), name


@pytest.mark.parametrize("name", sorted(rf.RIGS))
def test_fixture_chooses_its_own_map(files, name):
    m = read_motion(files[name])
    chosen, W = kit21_weights(m.skeleton)
    assert chosen == name
    assert np.allclose(W.sum(1), 1.0) and (W >= 0).all()  # convex combinations of nodes


@pytest.mark.parametrize("name", sorted(rf.RIGS))
def test_mapped_body_has_kit_proportions_stands_and_faces_forward(files, name):
    m = read_motion(files[name])
    b = body21(m, stature=1.75)
    assert abs(stature21(b) - 1.75) < 1e-9
    _check_body(b, 1.75, KNOWN.get(name, ()))
    # walking forward along the rig's own facing: the root moves along +Z
    assert b[-1, 0, 2] - b[0, 0, 2] > 0.2


def test_bandai_rest_pose_is_not_standing_and_does_not_matter(files):
    """Bandai Namco's rest pose lays bones along local x: nothing may rely on it."""
    m = read_motion(files["bandai"])
    rest = positions21(_still(m.skeleton))[0]
    assert abs(rest[I["LK"], 1] - rest[I["LH"], 1]) < 0.1  # the thigh does not hang down
    _check_body(body21(m, stature=1.6), 1.6, KNOWN["bandai"])


def test_specific_maps_win_over_generic_ones(files):
    mixamo = read_motion(files["mixamo"]).skeleton
    assert match_rig(mixamo, "bvh").name == "bvh"         # the generic map fits too
    assert kit21_weights(mixamo)[0] == "mixamo"
    bare = Skeleton([Joint(n.split(":")[-1], j.parent, j.offset, j.axes)
                     for n, j in zip(mixamo.names, mixamo.joints)])
    assert kit21_weights(bare)[0] == "bvh"                 # no namespace: generic naming
    daz = read_motion(files["cmu-bvh-daz"]).skeleton
    assert match_rig(daz, "poser").name == "poser" and kit21_weights(daz)[0] == "cmu-bvh-daz"
    cgspeed = read_motion(files["cmu-bvh"]).skeleton
    assert np.array_equal(match_rig(cgspeed, "bvh").weights[I["LE"]],
                          kit21_weights(cgspeed)[1][I["LE"]])


def test_smpl_arrays_and_bvh_names(files):
    rig = rf.RIGS["smpl"]
    names, _, _ = rf.parse(rig.tree)
    x = rf.positions(rig)                                    # (T, J, 3) metres, Y up, +Z
    smpl = x[:, [names.index(n) for n in SMPL_JOINT_NAMES]]  # (T, 22, 3) in SMPL order
    extra = np.concatenate([smpl, smpl[:, :2] + 0.1], axis=1)  # SMPL's 24 or SMPL-X's 55
    p21 = positions21_from_smpl(extra)
    assert p21.shape == (len(x), 21, 3) and np.allclose(p21, positions21_from_smpl(smpl))
    assert np.abs(p21 - positions21(read_motion(files["smpl"]))).max() < 1e-5
    _check_body(normalise21(p21, stature=1.7), 1.7)
    with pytest.raises(MotionlangError, match=r"\(\.\.\., >=22, 3\)"):
        positions21_from_smpl(smpl[:, :21])
    sk = read_motion(files["smpl"]).skeleton  # the same joints named as SMPL-to-BVH tools do
    renamed = [n.replace("left_", "L_").replace("right_", "R_").title() for n in sk.names]
    bvh_named = Skeleton([Joint(n, j.parent, j.offset, j.axes)
                          for n, j in zip(renamed, sk.joints)])
    assert "L_Hip" in renamed and kit21_weights(bvh_named)[0] == "smpl"


def test_mmm_cmu_and_cgspeed_choices_are_unchanged(files):
    sk = mmm_skeleton(1.8)
    name, W = kit21_weights(sk)
    nodes = {"root": "root_joint", "BP": "BPSegment_joint", "BT": "BTSegment_joint",
             "BLN": "BLNsegment_joint", "BUN": "BUNsegment_joint"}
    for side in "LR":
        nodes.update({f"{side}{j}": f"{side}{j}segment_joint" for j in "SEWHKA"})
        nodes.update({f"{side}Mrot": f"{side}Mrot_joint", f"{side}F": f"{side}Fx_joint"})
    expect = np.zeros_like(W)
    for k, body in enumerate(KIT21_NAMES):
        expect[k, sk.index(nodes[body])] = 1.0
    assert name == "mmm" and np.array_equal(W, expect)  # MMM positions are node positions
    assert kit21_weights(read_motion(files["cmu-bvh"]).skeleton)[0] == "cmu-bvh"


def test_real_kit_and_cmu_motions_map():
    kit = read_mmm(shared_file("kitml/00001_mmm.xml"))
    assert kit21_weights(kit.skeleton)[0] == "mmm"
    assert abs(stature21(positions21(kit)) - kit.meta["height"]) < 1e-6  # 1.82 m
    b = body21(kit)
    _check_body(b, 1.82)
    assert b[-1, 0, 2] > 1.0  # "A person is walking forwards."
    cmu = read_asf_amc(shared_file("cmu35/35.asf"), shared_file("cmu35/35_01.amc"))
    assert kit21_weights(cmu.skeleton)[0] == "cmu-asf"
    b = body21(cmu, stature=1.75)
    _check_body(b, 1.75)
    assert b[-1, 0, 2] > 1.0


# ------------------------------------------------------------------ user maps
RIGIFY = rf.Rig("rigify", 1.0, """
torso 0 0 0
  thigh.{s} 0.09 -0.03 0
    shin.{s} 0 -0.44 0
      foot.{s} 0 -0.43 0
        toe.{s} 0 -0.07 0.13
          * 0 0 0.05
  spine 0 0.10 0
    spine.001 0 0.12 0
      spine.003 0 0.26 0
        head 0 0.08 0
          * 0 0.2 0
      shoulder.{s} 0.03 0.22 0
        upper_arm.{s} 0.15 0 0
          forearm.{s} 0.30 0 0
            hand.{s} 0.25 0 0
              * 0.08 0 0
""", ("thigh.L", "thigh.R"), ("shin.L", "shin.R"), ("upper_arm.L", "upper_arm.R"),
    arms_down=75)
FILL = {"BP": "spine", "BT": "spine.001", "BLN": "spine.003", "BUN": "head"}
for _s in "LR":
    FILL.update({f"{_s}S": f"upper_arm.{_s}", f"{_s}E": f"forearm.{_s}", f"{_s}W": f"hand.{_s}",
                 f"{_s}H": f"thigh.{_s}", f"{_s}K": f"shin.{_s}", f"{_s}A": f"foot.{_s}",
                 f"{_s}F": f"toe.{_s}", f"{_s}Mrot": ["lerp", f"foot.{_s}", f"toe.{_s}", 0.4]})
FILL["root"] = ["mid", "thigh.L", "thigh.R"]


@pytest.fixture
def rigify(tmp_path):
    return read_motion(rf.write(RIGIFY, tmp_path))


def test_no_fit_error_names_the_unmatched_joints_and_the_way_out(rigify, tmp_path):
    assert match_rig(rigify.skeleton).name == "auto"   # no table fits; found automatically
    flipped = read_motion(rf.write(mirrored(RIGIFY), tmp_path, "flipped"))
    with pytest.raises(SkeletonError) as err:       # names and rest pose disagree on sides
        positions21(flipped)
    msg = str(err.value)
    assert "the names say thigh.R is on the right but the rest pose puts it on the left" in msg
    assert "\n" not in msg and "cannot be mapped" in msg
    assert "rig joints not matched: " in msg and "thigh.L" in msg and "upper_arm.R" in msg
    assert "toe.L_end" not in msg  # End Sites are not joints to map
    assert msg.endswith("pass --joint-map FILE; write a template with: "
                        "motionlang rig template FILE > map.json")


def test_template_filled_in_maps_the_rig(rigify, tmp_path):
    t = template_map(rigify.skeleton)
    assert set(t["joints"]) == set(KIT21_NAMES) and t["rig_joints"] == rigify.skeleton.names
    empty = {k for k, v in t["joints"].items() if v == ""}
    assert empty and "fill in" in t["about"]
    path = tmp_path / "map.json"
    path.write_text(json.dumps(t))
    with pytest.raises(SkeletonError, match=r"map\.json: body joint '\w+' is not filled in"):
        load_joint_map(path)
    path.write_text(json.dumps({**t, "joints": {**t["joints"], **FILL}}))
    jm = load_joint_map(path)
    assert jm["name"] == "bvh:rigify-map"
    assert jm["joints"]["root"] == ("mid", "thigh.L", "thigh.R")
    p = positions21(rigify, joint_map=path)
    assert np.allclose(p, positions21(rigify, joint_map=jm))
    _check_body(body21(rigify, joint_map=path, stature=1.8), 1.8)
    # a map given once at read time follows the motion into every feature
    rigify.meta["joint_map"] = jm
    assert np.allclose(positions21(rigify), p)
    assert np.allclose(positions21(rigify[::2]), p[::2])
    features = PositionFeatures().fit([rigify])
    assert features.encode(rigify).shape[1] == 66


@pytest.mark.parametrize("content,message", [
    ("{", "invalid JSON"),
    ("[]", "joint map must be a JSON object"),
    (json.dumps({"joints": {"root": "torso"}}), "missing body joints"),
    (json.dumps({"joints": {**FILL, "LT": "toe.L"}}), r"unknown body joints \['LT'\]"),
    (json.dumps({"joints": {**FILL, "LE": ["mid", "forearm.L"]}}),
     r"'LE' must be a joint name, \[\"mid\", a, b\]"),
    (json.dumps({"joints": {**FILL, "RE": ["lerp", "a", "b", "x"]}}), "'RE' must be"),
])
def test_bad_map_files_say_which_file_and_what(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(MotionlangError, match=message) as err:
        load_joint_map(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(MotionlangError, match="cannot read joint map"):
        load_joint_map(tmp_path / "absent.json")


def test_map_names_the_rig_lacks_and_explicit_built_in_maps(rigify, tmp_path):
    path = tmp_path / "typo.json"
    path.write_text(json.dumps({"name": "typo", "joints": {**FILL, "LE": "fore_arm.L"}}))
    with pytest.raises(SkeletonError, match=r"'typo' \(.*typo\.json\) names joints that rig "
                                            r"'bvh:rigify' lacks: fore_arm\.L"):
        positions21(rigify, joint_map=path)
    with pytest.raises(SkeletonError, match="with map 'bandai': it lacks UpperLeg_L, Upper"):
        positions21(rigify, "bandai")
    with pytest.raises(SkeletonError, match="unknown joint map 'nope'"):
        positions21(rigify, "nope")


def test_real_mit_and_bandai_motions_map(tmp_path):
    from helpers.data import bandai_takes
    mit = read_motion(shared_file("mit/motion.mat"))
    assert kit21_weights(mit.skeleton)[0] == "mit"
    # a real capture: the floor is the 5th percentile of the lowest foot joint, and MIT's
    # stance foot dips up to 2.6 cm below it in a few frames
    _check_body(body21(mit, stature=1.75), 1.75, sink=0.03)
    bandai_takes(["walk_normal_001", "run_normal_001"], tmp_path)
    for take in ("walk_normal_001", "run_normal_001"):
        m = read_motion(tmp_path / f"{take}.bvh")
        assert kit21_weights(m.skeleton)[0] == "bandai"
        b = body21(m, stature=1.75)
        _check_body(b, 1.75, KNOWN["bandai"], toes0=False)
        toes_ahead = b[:, [I["LF"], I["RF"]], 2] - b[:, [I["LA"], I["RA"]], 2]
        assert np.median(toes_ahead) > 0.05
        assert b[-1, 0, 2] - b[0, 0, 2] > 1.0        # both go forward, along +Z

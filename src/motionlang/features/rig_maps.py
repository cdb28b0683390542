"""Built-in maps from named rigs onto the 21-joint KIT body (``joint_map.KIT21_NAMES``).

A map gives, for each of the 21 body joints, a rig node (a name), ``("mid", a, b)`` (the
midpoint of two nodes) or ``("lerp", a, b, t)`` (``(1-t) a + t b``). A name may list
alternatives, ``"LeftToeBase|LeftToe"``: the first one the rig has is used. Names match
case-insensitively after dropping a ``namespace:`` prefix (``mixamorig:Hips`` is ``hips``).
BVH ``End Site`` nodes are named ``<parent>_end`` by ``formats.bvh``.

Automatic choice (``joint_map.kit21_weights``) takes the first map of :data:`RIG_MAPS` whose
every name is in the rig and whose ``signature`` patterns (regular expressions over the full
joint names) each match some joint. The list runs from the most specific naming to the most
generic one: a Mixamo rig also has every name of the generic ``bvh`` map, and CMU's
MotionBuilder-friendly BVH every name of both, so the specific map is reported.

Synthetic points, where a rig has no node for a body joint (facts that justify them):

* ``root``: the midpoint of the two hip joints everywhere but MMM. MMM's root lies on that
  line; the other rigs' pelvis nodes do not (CMU's and Mixamo's ``Hips`` sit above it,
  the DAZ-friendly ``hip`` below it, Bandai Namco's ``joint_Root`` on the floor).
* ``LMrot`` (mid-foot): only MMM has it; elsewhere it is put 40 % of the way from the ankle to
  the toe joint, MMM's own proportion (ankle-to-Mrot 31 of ankle-to-toe 82 mm per metre of
  stature).
* ``LF`` (toe joint): Poser-style BVH (Second Life, DAZ-friendly CMU) has no toe joint; its
  foot bone ends (the ``End Site``) at the ball of the foot, where Poser figures that have toes
  put ``lToe``.

Trunk joints are the rig's own spine nodes in order; rigs cut the trunk differently from MMM
(see ``joint_map``), so only the whole root-to-head-base chain is comparable across rigs.
"""
from __future__ import annotations

from dataclasses import dataclass

Spec = str | tuple


@dataclass(frozen=True)
class RigMap:
    """One named map: ``joints`` (all 21 body joints -> spec), what it is for (``about``)
    and the ``signature`` patterns a rig must also match to be recognised automatically."""

    name: str
    joints: dict
    about: str
    signature: tuple[str, ...] = ()


def _sided(table: dict[str, Spec], **sides: tuple[str, str]) -> dict[str, Spec]:
    """Expand entries written for the left side (keys ``L*``, names with ``{s}``-style
    placeholders) into both sides; ``sides`` maps each placeholder to (left, right)."""
    out: dict[str, Spec] = {}

    def fill(x, i):
        return x.format(**{k: v[i] for k, v in sides.items()}) if isinstance(x, str) else x

    for k, v in table.items():
        if not k.startswith("L"):
            out[k] = v
            continue
        for i, side in enumerate("LR"):
            out[side + k[1:]] = tuple(fill(x, i) for x in v) if isinstance(v, tuple) \
                else fill(v, i)
    return out


def _rig(name: str, about: str, trunk: tuple[str, str, str, str], limbs: tuple[str, ...],
         signature: tuple[str, ...] = (), **sides: tuple[str, str]) -> RigMap:
    """A map from the rig's BP, BT, BLN, BUN nodes and its left shoulder, elbow, wrist, hip,
    knee, ankle and toe names (placeholders filled from ``sides`` for each side)."""
    shoulder, elbow, wrist, hip, knee, ankle, toe = limbs
    table = _sided({"LS": shoulder, "LE": elbow, "LW": wrist, "LH": hip, "LK": knee,
                    "LA": ankle, "LMrot": ("lerp", ankle, toe, 0.4), "LF": toe}, **sides)
    table.update(zip(("BP", "BT", "BLN", "BUN"), trunk))
    table["root"] = ("mid", table["LH"], table["RH"])
    return RigMap(name, table, about, tuple(signature))


# MMM (KIT): every body joint is a node of the model.
_MMM = RigMap("mmm", _sided({
    "root": "root_joint", "BP": "BPSegment_joint", "BT": "BTSegment_joint",
    "BLN": "BLNsegment_joint", "BUN": "BUNsegment_joint",
    "LS": "{s}Ssegment_joint", "LE": "{s}Esegment_joint", "LW": "{s}Wsegment_joint",
    "LH": "{s}Hsegment_joint", "LK": "{s}Ksegment_joint", "LA": "{s}Asegment_joint",
    "LMrot": "{s}Mrot_joint", "LF": "{s}Fx_joint"}, s=("L", "R")),
    "KIT MMM reference model (KIT-ML motions)")

# The 21-joint body itself, as motionlang writes it (generated motions, ``-o x.bvh``):
# every body joint is the node of its own name, but the five leaves without DOFs (head
# base, wrists, toes) are written as End Sites and read back as ``<parent>_end``.
_BODY21_END = {"BUN": "BLN", "LW": "LE", "RW": "RE", "LF": "LMrot", "RF": "RMrot"}
_BODY21 = RigMap("body21", {n: f"{n}|{_BODY21_END[n]}_end" if n in _BODY21_END else n for n in (
    "root", "BP", "BT", "BLN", "BUN", "LS", "LE", "LW", "RS", "RE", "RW",
    "LH", "LK", "LA", "LMrot", "LF", "RH", "RK", "RA", "RMrot", "RF")},
    "motionlang's own 21-joint body (generated motions)")

RIG_MAPS: tuple[RigMap, ...] = (
    _MMM,
    _BODY21,
    # CMU ASF: a node sits at its bone's start, e.g. "ltibia" is the knee.
    _rig("cmu-asf", "CMU ASF/AMC skeletons",
         ("lowerback", "upperback", "lowerneck", "head"),
         ("{s}humerus", "{s}radius", "{s}wrist", "{s}femur", "{s}tibia", "{s}foot",
          "{s}toes"), s=("l", "r")),
    # cgspeed's first release, renamed for MotionBuilder: LowerBack = CMU lowerback,
    # Spine = upperback, Spine1 = thorax, Neck = lowerneck, Neck1 = upperneck.
    _rig("cmu-bvh", "CMU BVH, cgspeed MotionBuilder-friendly release (LHipJoint, LowerBack)",
         ("LowerBack", "Spine", "Neck", "Head"),
         ("{s}Arm", "{s}ForeArm", "{s}Hand", "{s}UpLeg", "{s}Leg", "{s}Foot",
          "{s}ToeBase"), s=("Left", "Right")),
    # cgspeed's 3ds Max Biped-friendly release: CMU spine names kept (lowerback, lowerneck),
    # Chest = upperback, Chest2 = thorax, Neck = upperneck; Biped limb names.
    _rig("cmu-bvh-max", "CMU BVH, cgspeed 3ds Max-friendly release (lowerback, Chest, "
         "lowerneck)", ("lowerback", "Chest", "lowerneck", "Head"),
         ("{s}Shoulder", "{s}Elbow", "{s}Wrist", "{s}Hip", "{s}Knee", "{s}Ankle",
          "{s}Toe"), s=("Left", "Right")),
    # cgspeed's DAZ-friendly release: Poser names plus lButtock/rButtock (CMU's hip joints).
    _rig("cmu-bvh-daz", "CMU BVH, cgspeed DAZ-friendly release (Poser names, lButtock)",
         ("abdomen", "chest", "neck", "head"),
         ("{s}Shldr", "{s}ForeArm", "{s}Hand", "{s}Thigh", "{s}Shin", "{s}Foot",
          "{s}Foot_end"), signature=("[lr]Buttock",), s=("l", "r")),
    # Bandai Namco Research Motion Dataset 1 and 2: one 22-joint rig, centimetres, Y up;
    # joint_Root stays on the floor below Hips.
    _rig("bandai", "Bandai Namco Research Motion Dataset rig (joint_Root, UpperLeg_L)",
         ("Spine", "Chest", "Neck", "Head"),
         ("UpperArm_{s}", "LowerArm_{s}", "Hand_{s}", "UpperLeg_{s}", "LowerLeg_{s}",
          "Foot_{s}", "Toes_{s}"), s=("L", "R")),
    # Reallusion iClone / Character Creator (CC3, CC4) base skeleton.
    _rig("cc", "iClone Character Creator rig (CC_Base_*)",
         ("CC_Base_Spine01", "CC_Base_Spine02", "CC_Base_NeckTwist01", "CC_Base_Head"),
         ("CC_Base_{s}_Upperarm", "CC_Base_{s}_Forearm", "CC_Base_{s}_Hand",
          "CC_Base_{s}_Thigh", "CC_Base_{s}_Calf", "CC_Base_{s}_Foot",
          "CC_Base_{s}_ToeBase"), s=("L", "R")),
    # Second Life's own skeleton (avatar_skeleton.xml; Collada/FBX avatar rigs): mFoot* is
    # the ball of the foot, mToe* the tip of the toes.
    _rig("second-life", "Second Life avatar skeleton (mPelvis, mTorso, mHipLeft)",
         ("mTorso", "mChest", "mNeck", "mHead"),
         ("mShoulder{s}", "mElbow{s}", "mWrist{s}", "mHip{s}", "mKnee{s}", "mAnkle{s}",
          "mFoot{s}"), s=("Left", "Right")),
    # Poser figures, DAZ Genesis 1/2, Second Life BVH uploads: hip, abdomen, chest, neck, head.
    _rig("poser", "Poser / DAZ / Second Life BVH naming (hip, abdomen, chest, lShldr)",
         ("abdomen", "chest", "neck", "head"),
         ("{s}Shldr", "{s}ForeArm", "{s}Hand", "{s}Thigh", "{s}Shin", "{s}Foot",
          "{s}Toe|{s}Foot_end"), s=("l", "r")),
    # SMPL / SMPL-X: the first 22 joints (also their common BVH names, Pelvis, L_Hip...).
    _rig("smpl", "SMPL / SMPL-X body joints (pelvis, left_hip; or Pelvis, L_Hip)",
         ("spine1", "spine2", "neck", "head"),
         ("{s}_shoulder|{c}_Shoulder", "{s}_elbow|{c}_Elbow", "{s}_wrist|{c}_Wrist",
          "{s}_hip|{c}_Hip", "{s}_knee|{c}_Knee", "{s}_ankle|{c}_Ankle",
          "{s}_foot|{c}_Foot"), s=("left", "right"), c=("L", "R")),
    _rig("mixamo", "Mixamo rig (mixamorig: namespace)", ("Spine", "Spine1", "Neck", "Head"),
         ("{s}Arm", "{s}ForeArm", "{s}Hand", "{s}UpLeg", "{s}Leg", "{s}Foot",
          "{s}ToeBase"), signature=(r"mixamorig\d*:.*",), s=("Left", "Right")),
    # MotionBuilder / HumanIK naming, also LAFAN1 (LeftToe) and Mixamo without namespace.
    _rig("bvh", "generic BVH naming (Hips, Spine, Spine1, LeftUpLeg, LeftArm)",
         ("Spine", "Spine1", "Neck", "Head"),
         ("{s}Arm", "{s}ForeArm", "{s}Hand", "{s}UpLeg", "{s}Leg", "{s}Foot",
          "{s}ToeBase|{s}Toe"), s=("Left", "Right")),
    # The MIT walking data as Taylor distributed it (formats.mit): no lumbar joint and no
    # head. The clavicles start together at the base of the neck (BLN); the lumbar joint
    # is put 40 % of the way from the pelvis to the thorax node (MMM: 0.040 of 0.100
    # stature from the hip line to BT), the head base 18 % of the thorax-to-neck span above
    # the neck (MMM: BLN to BUN 0.030 of stature, about 0.18 x MIT's 0.305 m span). Its
    # toes node is the tip of the foot, 0.110 of stature from the ankle: the toe joint is
    # put at MMM's 0.082 (75 % of the way) and the mid-foot at MMM's 0.031 (28 %).
    RigMap("mit", {**_sided({"LS": "{s}shoulder", "LE": "{s}elbow", "LW": "{s}wrist",
                             "LH": "{s}hip", "LK": "{s}knee", "LA": "{s}ankle",
                             "LMrot": ("lerp", "{s}ankle", "{s}toes", 0.28),
                             "LF": ("lerp", "{s}ankle", "{s}toes", 0.75)},
                            s=("l", "r")),
                   "root": ("mid", "lhip", "rhip"), "BP": ("lerp", "pelvis", "thorax", 0.4),
                   "BT": "thorax", "BLN": "lclavicle",
                   "BUN": ("lerp", "thorax", "lclavicle", 1.18)},
           "MIT walking data, Taylor's 18-node tree (pelvis, thorax, lclavicle)"),
    # The DeepMimic humanoid3d character (formats.deepmimic): its root sits on the hip line
    # as MMM's does; chest is the thorax joint (BT) and neck the base of the neck (BLN),
    # at shoulder height. The lumbar joint is put 40 % of the way from the root to the chest
    # (MMM: 0.040 of 0.100 stature from the hip line to BT), the head base 14 % of the
    # chest-to-neck span above the neck (MMM: BLN to BUN 0.030, BT to BLN 0.210 of stature).
    # It has no toe joints: its foot tip (the front of the sole) stands where MIT's toes node
    # does, so the toe joint and mid-foot are put as there (75 % and 28 % of the way). The
    # alternatives are the names a BVH written from it gives its end points.
    RigMap("deepmimic", {**_sided({"LS": "{s}_shoulder", "LE": "{s}_elbow",
                                   "LW": "{s}_wrist|{s}_elbow_end",
                                   "LH": "{s}_hip", "LK": "{s}_knee", "LA": "{s}_ankle",
                                   "LMrot": ("lerp", "{s}_ankle", "{s}_foot_tip|{s}_ankle_end",
                                             0.28),
                                   "LF": ("lerp", "{s}_ankle", "{s}_foot_tip|{s}_ankle_end",
                                          0.75)}, s=("left", "right")),
                         "root": ("mid", "left_hip", "right_hip"),
                         "BP": ("lerp", "root", "chest", 0.4), "BT": "chest", "BLN": "neck",
                         "BUN": ("lerp", "chest", "neck", 1.14)},
           "DeepMimic humanoid3d character (root, chest, neck, right_hip, left_foot_tip)"),
    # 3ds Max Character Studio / Biovision naming (also Xsens MVN BVH exports): here
    # LeftShoulder is the shoulder joint and LeftCollar the clavicle.
    _rig("biped", "3ds Max Biped / Biovision naming (Chest, Chest2, LeftCollar, LeftElbow)",
         ("Chest", "Chest2", "Neck", "Head"),
         ("{s}Shoulder", "{s}Elbow", "{s}Wrist", "{s}Hip", "{s}Knee", "{s}Ankle",
          "{s}Toe"), s=("Left", "Right")),
)

#: the 22 SMPL / SMPL-X body joints in their array order (Y up, facing +Z, metres)
SMPL_JOINT_NAMES: tuple[str, ...] = (
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar",
    "right_collar", "head", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
    "left_wrist", "right_wrist")

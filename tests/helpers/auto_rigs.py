"""Rigs no built-in map fits, in the kinds real data comes in (``helpers.rigs`` conventions:
x = the subject's left, y up, z forward), each with the map a person would write for it:

* ``biovision``: ``Hips, Ab, Chest, Chest2, LeftCollar, LeftShoulder ...`` and no toe joints
  (the foot ends in its End Site), centimetres.
* ``makehuman``: a small MakeHuman-style rig, lower-case ``l``/``r`` prefixes and ``.l``/``.r``
  suffixes, helper bones (``__jaw``) going up to the skull top and back down, face bones, five
  fingers and five toes; offsets of the public MakeHuman CMU conversion, rounded.
* ``cmu-lower``: CMU's ASF bone names in lower case (``hip, lhipjoint, lfemur``) as some BVH
  conversions write them, without the wrist and toe bones; the CMU conversion's offsets.
"""
from __future__ import annotations

import dataclasses

from helpers.rigs import Rig

BIOVISION = Rig("biovision", 0.01, """
Hips 0 0 0
  {side}Hip 9.5 -2 0
    {side}Knee 0 -44 0
      {side}Ankle 0 -42 0
        * 0 -6 14
  Ab 0 8 0
    Chest 0 12 0
      Chest2 0 12 0
        Neck 0 14 0
          Head 0 9 0
            * 0 17 0
        {side}Collar 3 9 0
          {side}Shoulder 13 0 0
            {side}Elbow 28 0 0
              {side}Wrist 24 0 0
                * 8 0 0
""", ("LeftHip", "RightHip"), ("LeftKnee", "RightKnee"), ("LeftShoulder", "RightShoulder"),
    arms_down=75)

MAKEHUMAN = Rig("makehuman", 0.01, """
hip 0 0 0
  abdomen 0 20.69 -0.73
    chest 0 11.70 -0.49
      neck 0 22.19 -2.19
        neck1 0 5.36 1.57
          head 0 5.36 1.57
            __jaw 0 13.60 -0.50
              jaw 0 -13.50 2.50
                tongue00 0 -6.84 4.38
                  tongue01 0 3.97 -3.76
                    * 0 0.43 2.92
                oris07.{l} 1.17 0.45 0.51
                  * 0.45 1.20 0.20
            special06.{l} 0 13.60 -0.50
              special05.{l} 2.11 0.15 5.60
                eye.{l} 0.86 -10.25 2.41
                  * 0.11 0.01 4.05
            __levator02.{l} 0 13.60 -0.50
              levator02.{l} 0.31 -11.32 11.60
                * 0.50 -1.68 -0.06
      {l}collar 2.68 19.26 -4.88
        {l}shoulder 8.78 -1.95 1.46
          {l}elbow 28.17 -1.71 0.49
            {l}hand 21.05 0 -0.63
              metacarpal1.{l} 2.82 -0.28 0.53
                finger2-1.{l} 6.29 0.27 2.52
                  finger2-2.{l} 2.31 -0.32 -0.06
                    * 2.38 -0.68 -0.18
              metacarpal2.{l} 2.82 -0.28 0.53
                finger3-1.{l} 6.31 0.63 0.32
                  finger3-2.{l} 3.02 -0.59 -0.09
                    * 2.34 -0.73 0
              __metacarpal3.{l} 2.82 -0.28 0.53
                metacarpal3.{l} 0.61 -0.16 -1.87
                  finger4-1.{l} 5.36 0.70 0.40
                    * 2.35 -0.62 -0.05
              __metacarpal4.{l} 2.82 -0.28 0.53
                metacarpal4.{l} 0.61 -0.16 -1.87
                  finger5-1.{l} 4.76 0.18 -1.11
                    * 1.80 -0.10 -0.08
              __{l}thumb 2.82 -0.28 0.53
                {l}thumb 0.28 -0.14 1.95
                  finger1-2.{l} 0.92 -2.15 1.55
                    * 2.52 -0.16 -0.51
  {l}buttock 8.78 4.35 1.22
    {l}hip 0 -1.71 -2.19
      {l}knee 0 -36.82 0.73
        {l}foot -0.73 -45.11 -5.12
          toe1-1.{l} -2.45 -4.05 13.19
            toe1-2.{l} 0.21 -0.65 2.43
              * 0.40 -0.83 2.73
          toe2-1.{l} -0.18 -4.30 13.33
            * 0.18 -0.32 2.04
          toe3-1.{l} 1.40 -4.46 13.08
            * 0.16 -0.25 1.81
          toe4-1.{l} 2.89 -4.48 12.38
            * 0.16 -0.33 1.49
          toe5-1.{l} 4.26 -4.47 11.71
            * 0.05 -0.27 0.98
""", ("lhip", "rhip"), ("lknee", "rknee"), ("lshoulder", "rshoulder"), arms_down=75)

CMU_LOWER = Rig("cmu-lower", 0.0254 / 0.45, """
hip 0 0 0
  {l}hipjoint 0 0 0
    {l}femur 1.778 -1.890 0.483
      {l}tibia 2.534 -6.963 0
        {l}foot 2.711 -7.448 0
          * 0.180 -0.494 2.225
  lowerback 0 0 0
    upperback 0.034 2.016 -0.222
      thorax 0.035 2.030 0.009
        lowerneck 0 0 0
          upperneck -0.002 1.705 0.209
            head 0.025 1.723 -0.222
              * 0.003 1.741 -0.098
        {l}clavicle 0 0 0
          {l}humerus 3.364 1.005 -0.377
            {l}radius 5.065 0 0
              {l}hand 3.602 0 0
                {l}fingers 0.6 0 0
                  * 0.5 0 0
                {l}thumb 0.3 0 0.3
                  * 0.3 0 0.3
""", ("lfemur", "rfemur"), ("ltibia", "rtibia"), ("lhumerus", "rhumerus"), arms_down=75,
    legs_in=20, order="ZYX")

AUTO_RIGS = {r.map: r for r in (BIOVISION, MAKEHUMAN, CMU_LOWER)}


def expected_map(hips, knees, ankles, toes, shoulders, elbows, wrists, trunk) -> dict:
    """The map a person writes: (left, right) joint names per limb joint, the four trunk
    joints (BP, BT, BLN, BUN); root and mid-foot as the built-in maps place them."""
    joints = dict(zip(("BP", "BT", "BLN", "BUN"), trunk))
    for i, s in enumerate("LR"):
        joints.update({f"{s}H": hips[i], f"{s}K": knees[i], f"{s}A": ankles[i],
                       f"{s}F": toes[i], f"{s}S": shoulders[i], f"{s}E": elbows[i],
                       f"{s}W": wrists[i], f"{s}Mrot": ["lerp", ankles[i], toes[i], 0.4]})
    joints["root"] = ["mid", hips[0], hips[1]]
    return {"name": "by-hand", "joints": joints}


def _lr(fmt: str) -> tuple[str, str]:
    return fmt.format(s="Left", l="l"), fmt.format(s="Right", l="r")


EXPECTED = {
    "biovision": expected_map(_lr("{s}Hip"), _lr("{s}Knee"), _lr("{s}Ankle"),
                              _lr("{s}Ankle_end"), _lr("{s}Shoulder"), _lr("{s}Elbow"),
                              _lr("{s}Wrist"), ("Ab", "Chest", "Neck", "Head")),
    "makehuman": expected_map(_lr("{l}hip"), _lr("{l}knee"), _lr("{l}foot"),
                              _lr("toe3-1.{l}"), _lr("{l}shoulder"), _lr("{l}elbow"),
                              _lr("{l}hand"), ("abdomen", "chest", "neck", "head")),
    "cmu-lower": expected_map(_lr("{l}femur"), _lr("{l}tibia"), _lr("{l}foot"),
                              _lr("{l}foot_end"), _lr("{l}humerus"), _lr("{l}radius"),
                              _lr("{l}hand"), ("lowerback", "upperback", "lowerneck", "head")),
}


def mirrored(rig: Rig) -> Rig:
    """The rig with every offset mirrored (x -> -x): its ``Left`` joints now on the subject's
    right, as a BVH written with a flipped axis has them."""
    lines = []
    for line in rig.tree.strip("\n").splitlines():
        name, x, y, z = line.split()
        indent = line[:len(line) - len(line.lstrip())]
        lines.append(f"{indent}{name} {-float(x):g} {y} {z}")
    return dataclasses.replace(rig, tree="\n".join(lines) + "\n")

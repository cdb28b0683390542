"""A map onto the 21-joint body found from a rig itself, for rigs no built-in table fits.

The rig's tree and rest pose give the structure, its joint names confirm it:

* **legs**: the two lowest leaves of the rest pose whose common ancestor is well above them
  (not two toes of one foot); that ancestor is the pelvis. Along each leg the two longest
  consecutive bones are thigh and shin, which gives hip, knee and ankle whatever extra
  joints (CMU's ``LHipJoint``, MakeHuman's ``lbuttock``) come before them. The toe joint is
  the ankle's child (of several toes, the middle one); a foot without toes ends in its
  ``End Site``, which is where Poser-style rigs end the foot (the ball, as ``rig_maps`` says).
* **axes**: up from ankles to hips, forward from ankles to toes, the subject's left their
  cross product (x = left, y up, z forward, as everywhere in motionlang).
* **arms**: the two leaves farthest apart across the body outside the legs (hands or finger
  tips in a T- or A-pose); their common ancestor is the chest; the two longest consecutive
  bones on the way are upper arm and forearm, so a clavicle is used if present and not
  needed if absent.
* **trunk**: the joints from the body's root (common ancestor of pelvis and chest) up to the
  chest are the lumbar (BP) and thorax (BT) joints as the built-in maps pick them; the chest's
  child that reaches highest starts the neck (BLN), and the head (BUN) is the joint named
  head on that chain, else where the chain branches or ends.
* **sides**: the rest pose's lateral axis and the names (``Left``/``Right``, ``l``/``r``
  prefixes, ``.L``/``_r`` suffixes, ``_L_`` infixes, whenever the other side's name exists).

Fingers, toes, face, twist and prop bones are ignored by construction. Every body joint gets
a confidence: structure alone ("topology") or structure its name agrees with ("name"). Left
and right found by the rest pose alone are doubted: a mirrored export would swap them
silently, which is the worst mistake a map can make.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from motionlang.features.rig_maps import Spec
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.skeleton import Skeleton

#: below this confidence a body joint is an error, not a guess
CONFIDENT = 0.5
ABOUT = "automatic: found from the rig's tree, rest pose and joint names"

_TWIST = re.compile(r"twist|roll|share|helper|adjust", re.IGNORECASE)
_END = re.compile(r"_end\d*$", re.IGNORECASE)
# limb words of several conventions (MotionBuilder, Biped, Poser, CMU ASF, Blender, SMPL)
_ROLE = {
    "S": r"shoulder|shldr|upper_?arm|uparm|humerus|(?<!fore)(?<!fore_)(?<!lower)(?<!lower_)arm",
    "E": r"elbow|fore_?arm|lower_?arm|lowarm|radius|ulna",
    "W": r"wrist|hand",
    "H": r"hip|thigh|up_?leg|upper_?leg|femur",
    "K": r"knee|shin|calf|tibia|lower_?leg|(?<!up)(?<!upper)(?<!upper_)(?<!up_)leg",
    "A": r"ankle|foot",
    "F": r"toe|ball",
    "BLN": r"neck",
    "BUN": r"head(?!_?top|_?end|_?nub)",
}


@dataclass
class Found:
    """How one body joint was found: its spec, ``how`` ("name": the structure and the
    joint's name agree, "topology": the structure alone), confidence in [0, 1]."""

    spec: Spec
    how: str
    confidence: float


@dataclass
class AutoMap:
    """The automatic map (``joints`` empty when the structure was not found), and the
    doubts behind every confidence below 1."""

    joints: dict[str, Found] = field(default_factory=dict)
    doubts: list[str] = field(default_factory=list)

    @property
    def confident(self) -> bool:
        return bool(self.joints) and all(f.confidence >= CONFIDENT
                                         for f in self.joints.values())

    def low(self) -> list[str]:
        """The doubts, or the body joints found with too little confidence."""
        return self.doubts or [k for k, f in self.joints.items() if f.confidence < CONFIDENT]


def _key(name: str) -> str:
    return name.rsplit(":", 1)[-1].lower()


def name_side(name: str, keys: set[str]) -> int:
    """+1 when the name says left, -1 right, 0 neither; a one-letter ``l``/``r`` counts
    only when the rig has the other side's name (``lowerback`` has no ``rowerback``)."""
    k = _key(name)
    if "left" in k or "right" in k:
        return 1 if "left" in k else -1
    swap = {"l": "r", "r": "l"}
    for m in re.finditer(r"(?:^|(?<=[._\-\s]))[lr](?=[._\-\s]|$)|^[lr](?=[a-z])", k):
        i = m.start()
        other = k[:i] + swap[k[i]] + k[i + 1:]
        if other in keys:
            return 1 if k[i] == "l" else -1
    return 0


def _rest(skeleton: Skeleton) -> np.ndarray:
    """(J, 3) rest-pose joint positions, metres, canonical frame (Y up)."""
    n = 1
    still = Motion(skeleton, 1.0, np.zeros((n, 3)), np.zeros((n, len(skeleton.root_axes))),
                   np.zeros((n, skeleton.ndof)))
    return still.positions()[0]


class _Tree:
    def __init__(self, skeleton: Skeleton):
        self.names = list(skeleton.names)
        self.keys = {_key(n) for n in self.names}
        self.parent = [int(p) for p in skeleton.parents]
        self.kids: list[list[int]] = [[] for _ in self.names]
        for j, p in enumerate(self.parent):
            if p >= 0:
                self.kids[p].append(j)
        self.P = _rest(skeleton)
        self.size = float(np.ptp(self.P, axis=0).max()) or 1.0

    def up_to(self, j: int) -> list[int]:
        """j and its ancestors, j first."""
        out = [j]
        while self.parent[out[-1]] >= 0:
            out.append(self.parent[out[-1]])
        return out

    def lca(self, a: int, b: int) -> int:
        above = set(self.up_to(a))
        return next(j for j in self.up_to(b) if j in above)

    def path(self, top: int, j: int) -> list[int]:
        """The joints from below ``top`` down to ``j``."""
        chain = self.up_to(j)
        return chain[:chain.index(top)][::-1]

    def leaves(self) -> list[int]:
        return [j for j, k in enumerate(self.kids) if not k]

    def below(self, j: int) -> set[int]:
        out, todo = set(), [j]
        while todo:
            out.add(todo[-1])
            todo.extend(self.kids[todo.pop()])
        return out

    def named(self, j: int, role: str) -> bool:
        return re.search(_ROLE[role], _key(self.names[j])) is not None


def _limb(t: _Tree, hub: int, tip: int) -> tuple[int, int, int, float]:
    """Along hub -> tip: (upper joint, middle joint, end joint, shorter / longer of the two
    bones between them), the two longest consecutive bones not starting at ``hub``."""
    pts = [hub]
    for j in t.path(hub, tip):
        if _TWIST.search(t.names[j]) or np.linalg.norm(t.P[j] - t.P[pts[-1]]) < 1e-4 * t.size:
            continue
        pts.append(j)
    seg = np.linalg.norm(np.diff(t.P[pts], axis=0), axis=1)
    if len(seg) < 3:
        return pts[-1], pts[-1], pts[-1], 0.0
    k = 1 + int(np.argmax(seg[1:-1] + seg[2:]))
    a, b = seg[k], seg[k + 1]
    return pts[k], pts[k + 1], pts[k + 2], float(min(a, b) / max(a, b))


def _toe(t: _Tree, ankle: int) -> int | None:
    """The ankle's child nearest the middle of its children (the middle toe of five)."""
    kids = t.kids[ankle]
    if not kids:
        return None
    mid = t.P[kids].mean(axis=0)
    return min(kids, key=lambda j: float(np.linalg.norm(t.P[j] - mid)))


def auto_map(skeleton: Skeleton) -> AutoMap:
    """Find the 21 body joints in a rig (see the module docstring); never raises: a rig
    whose structure is not found gets an empty map and the reason as its doubt."""
    t, out = _Tree(skeleton), AutoMap()
    P, size = t.P, t.size
    leaves = t.leaves()
    foot1 = min(leaves, key=lambda j: P[j, 1])
    floor = P[foot1, 1]
    other = [j for j in leaves if P[t.lca(j, foot1), 1] > floor + 0.25 * size]
    if not other:
        out.doubts.append("no two legs found (no second low branch apart from the first)")
        return out
    foot2 = min(other, key=lambda j: P[j, 1])
    pelvis = t.lca(foot1, foot2)
    legs = [_limb(t, pelvis, f) for f in (foot1, foot2)]
    if min(leg[3] for leg in legs) == 0.0 or legs[0][0] == legs[1][0]:
        out.doubts.append("the legs have too few joints for hip, knee and ankle")
        return out
    toes = [_toe(t, leg[2]) for leg in legs]
    up = P[[leg[0] for leg in legs]].mean(0) - P[[leg[2] for leg in legs]].mean(0)
    up /= np.linalg.norm(up)
    fwd = sum((P[f] - P[leg[2]] for f, leg in zip(toes, legs) if f is not None), np.zeros(3))
    fwd -= (fwd @ up) * up
    left = np.cross(up, fwd / np.linalg.norm(fwd)) if np.linalg.norm(fwd) > 0.01 * size \
        else None
    across = P[legs[0][0]] - P[legs[1][0]]
    across -= (across @ up) * up
    across /= np.linalg.norm(across) or 1.0

    in_legs = set().union(*(t.below(t.path(pelvis, f)[0]) for f in (foot1, foot2)))
    rest = [j for j in leaves if j not in in_legs]
    if len(rest) < 3:
        out.doubts.append("no two arms and a head found above the legs")
        return out
    centre = P[pelvis]
    tips = (max(rest, key=lambda j: (P[j] - centre) @ across),
            min(rest, key=lambda j: (P[j] - centre) @ across))
    chest = t.lca(*tips)
    spread = float((P[tips[0]] - P[tips[1]]) @ across)
    if chest in in_legs or (P[chest] - centre) @ up <= 0 or spread < 0.2 * size:
        out.doubts.append("no two arms found branching above the pelvis")
        return out
    arms = [_limb(t, chest, tip) for tip in tips]
    if min(arm[3] for arm in arms) == 0.0:
        out.doubts.append("the arms have too few joints for shoulder, elbow and wrist")
        return out
    on_arms = {j for tip in tips for j in t.path(chest, tip)}
    heads = [c for c in t.kids[chest] if c not in on_arms]
    if not heads:
        out.doubts.append("no neck or head found above the chest")
        return out
    neck = max(heads, key=lambda c: max(P[j] @ up for j in t.below(c)))
    root = t.lca(pelvis, chest)
    _trunk(t, out, root, chest, neck)
    for side_names, pair, found in (("LS LE LW", arms, "arms"), ("LH LK LA", legs, "legs")):
        _sides(t, out, side_names, pair, left, found, toes if found == "legs" else None)
    a = {k: out.joints[k] for k in ("LH", "RH")}
    out.joints["root"] = Found(("mid", a["LH"].spec, a["RH"].spec), "topology",
                               min(f.confidence for f in a.values()))
    out.joints = {k: out.joints[k] for k in _ORDER}
    return out


_ORDER = ("root", "BP", "BT", "BLN", "BUN", "LS", "LE", "LW", "RS", "RE", "RW",
          "LH", "LK", "LA", "LMrot", "LF", "RH", "RK", "RA", "RMrot", "RF")


def _found(t: _Tree, j: int, role: str, conf: float) -> Found:
    named = t.named(j, role)
    return Found(t.names[j], "name" if named else "topology", conf if named else conf * 0.9)


def _trunk(t: _Tree, out: AutoMap, root: int, chest: int, neck: int) -> None:
    spine = t.path(root, chest)
    J = out.joints
    if len(spine) >= 2:
        J["BP"] = Found(t.names[spine[0]], "topology", 0.9)
        J["BT"] = Found(t.names[spine[1]], "topology", 0.9)
    else:   # the chest sits on the root: the lumbar joint where MMM has it (rig_maps: mit)
        J["BP"] = Found(("lerp", t.names[root], t.names[chest], 0.4), "topology", 0.7)
        J["BT"] = Found(t.names[chest], "topology", 0.8)
    chain = [neck]
    while len(k := [c for c in t.kids[chain[-1]] if not _END.search(t.names[c])]) == 1:
        chain.append(k[0])
    head = next((j for j in chain if t.named(j, "BUN")), None)
    J["BUN"] = _found(t, head, "BUN", 1.0) if head is not None else \
        Found(t.names[chain[-1]], "topology", 0.75)
    if J["BUN"].spec == t.names[neck]:   # no neck joint: halfway from the chest
        J["BLN"] = Found(("lerp", t.names[chest], t.names[neck], 0.5), "topology", 0.6)
    else:
        J["BLN"] = _found(t, neck, "BLN", 1.0)


def _sides(t: _Tree, out: AutoMap, roles: str, pair: list, left, what: str, toes) -> None:
    """Name the two limbs of ``pair`` left and right, and add their joints."""
    geo = [float(np.sign((t.P[limb[0]] - t.P[pair[1 - i][0]]) @ left)) if left is not None
           else 0.0 for i, limb in enumerate(pair)]
    said = [sum(name_side(t.names[j], t.keys) for j in limb[:3]) for limb in pair]
    said = [float(np.sign(s)) for s in said]
    first_left = geo[0] > 0 if geo[0] else said[0] > 0 or said[1] < 0
    order = (0, 1) if first_left else (1, 0)
    names_agree = said[order[0]] >= 0 and said[order[1]] <= 0 and any(said)
    if geo[0] and not any(said):
        side, doubt = 0.45, f"{what}: left and right from the rest pose alone, no joint name " \
                            "says which side"
    elif geo[0] and not names_agree:
        side, doubt = 0.2, f"{what}: the names say {t.names[pair[order[0]][0]]} is on the " \
                           "right but the rest pose puts it on the left"
    elif not geo[0]:
        side, doubt = (0.8, "") if names_agree else \
            (0.2, f"{what}: neither the rest pose nor the names say which side is left")
    else:
        side, doubt = 1.0, ""
    if doubt:
        out.doubts.append(doubt)
    for s, i in zip("LR", order):
        upper, middle, end, ratio = pair[i]
        conf = min(side, 1.0 if ratio >= 0.6 else 0.4)
        if ratio < 0.6:
            out.doubts.append(f"{what}: {t.names[upper]}-{t.names[middle]} and "
                              f"{t.names[middle]}-{t.names[end]} differ too much in length")
        for role, j in zip(roles.split(), (upper, middle, end)):
            f = _found(t, j, role[1:], conf)
            wrong = [r for r in ("S", "E", "W", "H", "K", "A") if r != role[1:]
                     and t.named(j, r) and not t.named(j, role[1:])]
            if wrong and role[1:] in "EWKA":
                out.doubts.append(f"{s}{role[1:]} <- {t.names[j]}: its name says "
                                  f"{'/'.join(wrong)}")
                f.confidence = min(f.confidence, 0.4)
            out.joints[s + role[1:]] = f
        if toes is None:
            continue
        toe = toes[i]
        if toe is None:
            out.doubts.append(f"{t.names[end]}: no toe joint or foot end to place the toes")
            out.joints[s + "F"] = Found(t.names[end], "topology", 0.3)
        else:
            out.joints[s + "F"] = _found(t, toe, "F", min(conf, 0.9))
        out.joints[s + "Mrot"] = Found(("lerp", t.names[end], out.joints[s + "F"].spec, 0.4),
                                       "topology", out.joints[s + "F"].confidence)

"""The 21-joint KIT layout, and maps onto it from every supported rig.

The 21 joints are the ones the processed KIT-ML position data of later work (language2pose,
Ghosh et al. 2021, HumanML3D's ``kit``) uses, named after the MMM segments, in this order::

     0 root   MMM root (pelvis, at hip-joint height)       11 LH     left hip
     1 BP     pelvis/lumbar joint (BPSegment)              12 LK     left knee
     2 BT     thorax/lower-spine joint (BTSegment)         13 LA     left ankle
     3 BLN    lower neck (C7, BLNsegment)                  14 LMrot  left mid-foot (metatarsal)
     4 BUN    upper neck / head base (BUNsegment)          15 LF     left toe joint
     5 LS  6 LE  7 LW   left shoulder, elbow, wrist        16-20  RH RK RA RMrot RF (right leg)
     8 RS  9 RE 10 RW   right shoulder, elbow, wrist

Left means the subject's left (MMM's ``L*`` nodes, CMU's ``l*`` bones, BVH ``Left*``).
Tree: root-BP-BT-BLN-BUN; BLN-shoulders-elbows-wrists; root-hips-knees-ankles-midfoot-toes.

A map sends each of the 21 joints to a rig node name, ``("mid", a, b)`` or
``("lerp", a, b, t)``. The built-in maps (MMM, CMU ASF and its BVH conversions, Bandai Namco,
iClone CC, Second Life, Poser/DAZ, SMPL, Mixamo, generic BVH and Biped namings) and the facts
behind their synthetic points are in :mod:`.rig_maps`; one is chosen from the joint names; a
rig none fits is mapped from its tree, rest pose and names (:mod:`.rig_auto`). A
user's own map is a JSON file (:func:`load_joint_map`, :func:`template_map`)::

    {"name": "my-rig", "joints": {"root": ["mid", "L_hip", "R_hip"], "BP": "spine_01", ...,
                                  "LMrot": ["lerp", "L_ankle", "L_ball", 0.4], ...}}

given to :func:`positions21` as ``joint_map`` or kept in ``motion.meta["joint_map"]``.

Limb bones of CMU subject 35 and KIT 00001 agree within 20 % after scaling by stature; the
four trunk bones do not, whatever CMU spine nodes are chosen (MMM puts the lumbar joint BP
0.04 H above the hip line, CMU's nearest spine nodes are at 0 and 0.066 H), so only the whole
root-to-head-base chain is comparable (``tests/test_joint_map.py`` checks both facts).
"""
from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features.rig_auto import ABOUT, auto_map
from motionlang.features.rig_maps import RIG_MAPS, SMPL_JOINT_NAMES, RigMap, Spec
from motionlang.formats import read_joint_map  # the one reader of the file
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.skeleton import Skeleton
from motionlang.utils.sidecar import check_name

KIT21_NAMES: tuple[str, ...] = (
    "root", "BP", "BT", "BLN", "BUN", "LS", "LE", "LW", "RS", "RE", "RW",
    "LH", "LK", "LA", "LMrot", "LF", "RH", "RK", "RA", "RMrot", "RF")
#: parent index of each of the 21 joints (-1 for the root); bones are (i, KIT21_PARENTS[i]).
KIT21_PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3, 3, 5, 6, 3, 8, 9, 0, 11, 12, 13, 14, 0, 16, 17, 18, 19)
#: left/right partner of each joint (itself on the midline), for mirroring positions.
KIT21_MIRROR: tuple[int, ...] = tuple(
    KIT21_NAMES.index(("R" + n[1:]) if n[0] == "L" else ("L" + n[1:]) if n[0] == "R" else n)
    for n in KIT21_NAMES)
#: the toe joints (LF, RF): the part of a foot that is down longest; foot contact is read there
TOES: tuple[int, ...] = (KIT21_NAMES.index("LF"), KIT21_NAMES.index("RF"))

#: named maps (``rig_maps.RIG_MAPS``), tried in this order, most specific first.
JOINT_MAPS: dict[str, dict[str, Spec]] = {m.name: m.joints for m in RIG_MAPS}
_BY_NAME = {m.name: m for m in RIG_MAPS}
HINT = "pass --joint-map FILE; write a template with: motionlang rig template FILE > map.json"


@dataclass
class RigMatch:
    """A map applied to one rig: ``weights`` (21, J) give ``positions21 = W @ positions``;
    ``sources`` says where each body joint comes from, in the rig's own names."""

    name: str
    about: str
    weights: np.ndarray
    sources: dict[str, Spec]
    #: body joint -> (how it was found: "table", "user", "name" or "topology", confidence)
    how: dict[str, tuple[str, float]] | None = None


def _key(name: str) -> str:
    return name.rsplit(":", 1)[-1].lower()


def _parts(spec: Spec) -> list[tuple[str, float]]:
    if isinstance(spec, str):
        return [(spec, 1.0)]
    if spec[0] == "mid":
        return [(spec[1], 0.5), (spec[2], 0.5)]
    return [(spec[1], 1.0 - spec[3]), (spec[2], spec[3])]  # ("lerp", a, b, t)


def _resolve(names: list[str], table: dict[str, Spec]
             ) -> tuple[np.ndarray, list[str], dict[str, Spec]]:
    """-> W (21, J), the names the rig lacks, and each resolvable body joint's spec written
    with the rig's own names (``"a|b"`` alternatives: the first the rig has)."""
    index: dict[str, int] = {}
    for i, n in enumerate(names):
        index.setdefault(_key(n), i)
    W = np.zeros((len(KIT21_NAMES), len(names)))
    missing, sources = [], {}
    for k, body in enumerate(KIT21_NAMES):
        spec, found = table[body], []
        for src, w in _parts(spec):
            j = next((index[_key(a)] for a in src.split("|") if _key(a) in index), None)
            if j is None:
                missing.append(src)
            else:
                W[k, j] += w
                found.append(names[j])
        if len(found) == len(_parts(spec)):
            sources[body] = found[0] if isinstance(spec, str) else (spec[0], *found, *spec[3:])
    return W, missing, sources


def _signed(rig: RigMap, names: list[str]) -> bool:
    return all(any(re.fullmatch(p, n, re.IGNORECASE) for n in names) for p in rig.signature)


def _listed(items: list[str], limit: int = 12) -> str:
    items = list(dict.fromkeys(items))
    more = f", ... ({len(items) - limit} more)" if len(items) > limit else ""
    return ", ".join(items[:limit]) + more


def _used(sources: dict[str, Spec]) -> set[str]:
    """The rig joints a map's sources read."""
    return {n for s in sources.values() for n in ([s] if isinstance(s, str) else s[1:3])}


def _is_end_site(name: str) -> bool:
    return re.search(r"_end\d*$", name, re.IGNORECASE) is not None


def closest_map(skeleton: Skeleton) -> tuple[RigMap, list[str], dict[str, Spec]]:
    """The built-in map the rig comes nearest to (its signature matches, it places the most
    body joints, lacks the fewest names; then table order): (map, names it lacks, the body
    joints it can place, in the rig's names)."""
    names = list(skeleton.names)
    best = None
    for rig in RIG_MAPS:
        _, missing, sources = _resolve(names, rig.joints)
        score = (not _signed(rig, names), -len(sources), len(set(missing)))
        if best is None or score < best[0]:
            best = (score, rig, missing, sources)
    return best[1], best[2], best[3]


def match_rig(skeleton: Skeleton, map_name: str | None = None,
              joint_map: dict | str | Path | None = None) -> RigMatch:
    """Map a skeleton onto the 21 body joints with ``joint_map`` (a map dict or a JSON file),
    else the built-in map ``map_name``, else the first built-in map that fits its names.

    Raises:
        SkeletonError: the map names joints the rig lacks, or no built-in map fits (the
            message names the rig's joints the closest map leaves unmatched).
    """
    names, label = list(skeleton.names), skeleton.name
    if joint_map is not None:
        jm = as_joint_map(joint_map)
        W, missing, sources = _resolve(names, jm["joints"])
        if missing:
            raise SkeletonError(f"joint map {jm['name']!r} ({jm['source']}) names joints that "
                                f"rig {label!r} lacks: {_listed(missing)}; its joints "
                                f"(motionlang rig show FILE lists them all): "
                                f"{_listed(names)}")
        return RigMatch(jm["name"], f"user map {jm['source']}", W, sources,
                        {k: ("user", 1.0) for k in KIT21_NAMES})
    if map_name is not None:
        if map_name not in _BY_NAME:
            raise SkeletonError(f"unknown joint map {map_name!r}; known: {sorted(_BY_NAME)}")
        rigs = [_BY_NAME[map_name]]
    else:
        rigs = list(RIG_MAPS)
    for rig in rigs:
        if map_name is None and not _signed(rig, names):
            continue
        W, missing, sources = _resolve(names, rig.joints)
        if not missing:
            return RigMatch(rig.name, rig.about, W, sources,
                            {k: ("table", 1.0) for k in KIT21_NAMES})
    if map_name is not None:
        raise SkeletonError(f"skeleton {label!r} cannot be mapped to the 21 KIT joints with "
                            f"map {map_name!r}: it lacks {_listed(missing)}; {HINT}")
    auto = auto_map(skeleton)
    if auto.confident:
        W, missing, sources = _resolve(names, {k: f.spec for k, f in auto.joints.items()})
        return RigMatch("auto", ABOUT, W, sources,
                        {k: (f.how, f.confidence) for k, f in auto.joints.items()})
    rig, missing, sources = closest_map(skeleton)
    used = _used(sources)
    unmatched = [n for n in names if n not in used and not _is_end_site(n)]
    closest = f" (closest map {rig.name!r} lacks {_listed(missing)})" if sources else ""
    raise SkeletonError(f"skeleton {label!r} cannot be mapped to the 21 KIT joints: no "
                        f"built-in map fits; rig joints not matched: {_listed(unmatched, 40)}"
                        f"{closest}; automatic map unsure: {'; '.join(auto.low())}; {HINT}")


def kit21_weights(skeleton: Skeleton, map_name: str | None = None, *,
                  joint_map: dict | str | Path | None = None) -> tuple[str, np.ndarray]:
    """Pick the joint map for a skeleton (see :func:`match_rig`).

    Returns:
        (map name, W (21, J)) with ``positions21 = W @ positions`` per frame.
    """
    m = match_rig(skeleton, map_name, joint_map)
    return m.name, m.weights


def positions21(motion: Motion, map_name: str | None = None,
                joint_map: dict | str | Path | None = None) -> np.ndarray:
    """(T, 21, 3) metres, canonical frame (Y up), of the KIT joints ``KIT21_NAMES``.

    The map is ``joint_map`` (a map dict or JSON path), else the built-in ``map_name`` (a
    key of ``JOINT_MAPS``), else ``motion.meta["joint_map"]`` (a map given when the motion
    was read), else chosen from the joint names.

    Raises:
        SkeletonError: the skeleton lacks joints the map needs, or no map fits.
    """
    if joint_map is None and map_name is None:
        joint_map = motion.meta.get("joint_map")
    _, W = kit21_weights(motion.skeleton, map_name, joint_map=joint_map)
    used = np.flatnonzero(np.abs(W).sum(axis=0))   # only the joints the map reads
    return np.matmul(W[:, used], motion.positions(used))


def positions21_from_smpl(joints) -> np.ndarray:
    """SMPL / SMPL-X joint positions (..., J >= 22, 3), first 22 in ``SMPL_JOINT_NAMES``
    order, -> (..., 21, 3) KIT joints in the same frame and unit (map ``smpl``)."""
    p = np.asarray(joints, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 3 or p.shape[-2] < len(SMPL_JOINT_NAMES):
        raise MotionlangError(f"SMPL joints must be (..., >=22, 3), got {p.shape}")
    W, _, _ = _resolve(list(SMPL_JOINT_NAMES), _BY_NAME["smpl"].joints)
    return np.einsum("kj,...jc->...kc", W, p[..., :len(SMPL_JOINT_NAMES), :])


_PARENTS21 = np.array(KIT21_PARENTS[1:])


def bone_lengths21(pos21: np.ndarray) -> np.ndarray:
    """pos21 (..., 21, 3) -> (..., 20) lengths of the bones (i, parent(i)), i = 1..20."""
    # the children are joints 1..20 in order: a slice, and np.take for the parents, copy
    # far less than fancy indexing does on long takes
    d = pos21[..., 1:, :] - np.take(pos21, _PARENTS21, axis=-2)
    return np.sqrt(np.einsum("...c,...c->...", d, d))


# ----------------------------------------------------------------------- user maps (JSON)
def _check_spec(body: str, v, where: str) -> Spec:
    def bad(why: str) -> SkeletonError:
        return SkeletonError(f"{where}: body joint {body!r} {why}")

    if isinstance(v, str):
        if not v.strip():
            raise bad('is not filled in (""); give one of the rig\'s joints')
        return check_name(v.strip(), where, f"joint name of {body!r}")
    ok = isinstance(v, (list, tuple)) and (
        (len(v) == 3 and v[0] == "mid") or
        (len(v) == 4 and v[0] == "lerp" and isinstance(v[3], (int, float))
         and not isinstance(v[3], bool) and np.isfinite(v[3])))
    if not ok or not all(isinstance(x, str) and x.strip() for x in v[1:3]):
        raise bad(f'must be a joint name, ["mid", a, b] or ["lerp", a, b, t]; got '
                  f"{json.dumps(v)[:80]}")
    a, b = (check_name(x.strip(), where, f"joint name of {body!r}") for x in v[1:3])
    return (v[0], a, b, *[float(t) for t in v[3:]])


def check_joint_map(d, where: str = "joint map") -> dict:
    """Validate a map dict -> ``{"name", "joints" (21 specs, lists as tuples), "source"}``.
    Whether the names exist is checked when the map meets a rig (:func:`match_rig`)."""
    if not isinstance(d, dict) or not isinstance(d.get("joints"), dict):
        raise SkeletonError(f'{where}: expected a JSON object with a "joints" object mapping '
                            f"each of the 21 body joints ({', '.join(KIT21_NAMES)})")
    joints = d["joints"]
    lacking = [k for k in KIT21_NAMES if k not in joints]
    unknown = [k for k in joints if k not in KIT21_NAMES]
    if lacking or unknown:
        raise SkeletonError(f"{where}: " + "; ".join(
            ([f"missing body joints {lacking}"] if lacking else []) +
            ([f"unknown body joints {unknown} (the 21 are {', '.join(KIT21_NAMES)})"]
             if unknown else [])))
    source = d.get("source") or d.get("path") or where  # "path": formats.read_joint_map
    return {"name": str(d.get("name") or source), "source": str(source),
            "joints": {k: _check_spec(k, joints[k], where) for k in KIT21_NAMES}}


def load_joint_map(path: str | Path) -> dict:
    """Read and check a joint map JSON file (see the module docstring)."""
    path = Path(path)
    d = read_joint_map(path)
    d = {**d, "name": d.get("name") or path.stem, "source": str(path)}
    return check_joint_map(d, str(path))


def as_joint_map(joint_map: dict | str | Path) -> dict:
    """A checked map from a map dict or the path of a JSON map."""
    if isinstance(joint_map, (str, Path)):
        return load_joint_map(joint_map)
    where = "joint map"
    if isinstance(joint_map, dict):
        where = str(joint_map.get("source") or joint_map.get("path") or joint_map.get("name")
                    or where)
    return check_joint_map(joint_map, where)


def template_map(skeleton: Skeleton) -> dict:
    """A map to fill in for a rig: the closest built-in map's entries written with the rig's
    names, ``""`` where it has no match, and the rig's joints (``rig_joints``) to use."""
    rig, _, sources = closest_map(skeleton)
    joints = {k: list(sources[k]) if isinstance(sources.get(k), tuple) else sources.get(k, "")
              for k in KIT21_NAMES}
    todo = [k for k, v in joints.items() if v == ""]
    guesses = (f"guesses from the built-in map {rig.name!r}" if len(todo) < len(joints)
               else "no built-in map matches its joints")
    fill = (f"fill in {', '.join(todo)} with joints of rig_joints" if todo
            else "every body joint is filled in")
    return {"name": f"{skeleton.name}-map",
            "about": f'{guesses}; {fill} (a name, ["mid", a, b] or ["lerp", a, b, t]); '
                     "left = the subject's left",
            "joints": joints, "rig_joints": list(skeleton.names)}


def rig_summary(skeleton: Skeleton, joint_map: dict | str | Path | None = None) -> dict:
    """How a rig maps onto the 21-joint body (:func:`match_rig`, ``joint_map`` as there):
    ``{"rig", "joints" (its joints, end sites left out), "end_sites" (how many), "map",
    "about", "body" ({body joint: its source in the rig's names}), "how" ({body joint:
    [how it was found, confidence]}), "unused" (the rig's joints the map does not read)}``.

    Raises:
        SkeletonError: as :func:`match_rig`.
    """
    m = match_rig(skeleton, joint_map=joint_map)
    names = list(skeleton.names)
    joints = [n for n in names if not _is_end_site(n)]
    body = {k: m.sources[k] for k in KIT21_NAMES}
    used = _used(body)
    return {"rig": skeleton.name, "joints": joints, "end_sites": len(names) - len(joints),
            "map": m.name, "about": m.about, "body": body,
            "how": {k: list(m.how[k]) if m.how else ["table", 1.0] for k in KIT21_NAMES},
            "unused": [n for n in joints if n not in used]}


def spec_text(spec: Spec) -> str:
    """A body joint's source as text: ``"Hips"``, ``"mid(a, b)"``, ``"lerp(a, b, 0.4)"``."""
    if isinstance(spec, str):
        return spec
    args = ", ".join(str(a) if isinstance(a, str) else f"{a:g}" for a in spec[1:])
    return f"{spec[0]}({args})"


def summary_text(s: dict) -> str:
    """A :func:`rig_summary` as ``motionlang rig show`` prints it."""
    import textwrap
    wrap = textwrap.TextWrapper(width=92, initial_indent=" " * 11, subsequent_indent=" " * 11)
    lines = [f"  rig      {s['rig']}: {len(s['joints'])} joints"
             + (f" (+ {s['end_sites']} end sites)" if s["end_sites"] else ""),
             wrap.fill(", ".join(s["joints"])), f"  map      {s['map']}: {s['about']}",
             "  body joint, how found, confidence <- rig joint",
             *(f"    {k:<6} {s['how'][k][0]:<8} {s['how'][k][1]:4.2f} <- {spec_text(spec)}"
               for k, spec in s["body"].items())]
    if s["unused"]:
        lines.append("  unused   " + wrap.fill(", ".join(s["unused"])).lstrip())
    return "\n".join(lines)


def map_json(d: dict) -> str:
    """A joint map (e.g. :func:`template_map`'s) as JSON with one line per body joint, to
    edit by hand (``json.dumps`` would spread every ``["mid", a, b]`` over four lines)."""
    lines = []
    for key, value in d.items():
        if isinstance(value, dict):
            inner = [f"    {json.dumps(k)}: {json.dumps(v)}" for k, v in value.items()]
            lines.append(f"  {json.dumps(key)}: {{\n" + ",\n".join(inner) + "\n  }")
        else:
            lines.append(f"  {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}"

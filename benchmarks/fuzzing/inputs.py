"""Inputs that fuzz the readers: random edits of valid files (:func:`mutate`) and files
crafted to stress one reader (:func:`crafted`).

Both are driven by ``choose(n)``, an integer in ``range(n)``, so that hypothesis
(``lambda n: draw(st.integers(0, n - 1))``: reproducible, shrinkable) and a seeded
``random.Random`` (``rng.randrange``) drive them alike.

What they cover: truncation, flipped bytes, MAT element tags given another type or size (a
double array's type 09 -> 08 among them), deleted, duplicated, swapped and repeated lines
(inputs thousands of lines longer), extreme and broken numbers (``1e999``, ``nan``,
5,000-digit integers, ``²``), words moved around; for XML, encoding declarations
(``utf-32``, unknown ones, files really in UTF-16) and DTDs (billion laughs, a quadratic
blow-up, external entities); deep and wide skeletons; ASF bone lists child-before-parent;
BVH and AMC files declaring or holding far more frames than is sane; MAT files whose fields
have the wrong type (text, cells, structs, complex numbers where numbers belong), are
missing, or hold NaN; HumanML3D-layout folders (``h3d``, a tar of the folder, see
:func:`.seeds.pack_h3d`) whose ``.npy`` headers are corrupt, truncated, declare other or
huge shapes or object/complex/text dtypes, whose data holds NaN or inf, whose caption lines
have odd ``#`` counts, broken, reversed or negative time spans, other encodings or very long
lines, whose split files name missing ids or paths (``../x``, ``/etc/passwd``), and files
missing, emptied or added.

The byte-level edits are in :mod:`.edits`, the HumanML3D layout's inputs in
:mod:`.h3d_inputs`.
"""
from __future__ import annotations

import numpy as np

from .edits import SPECIAL, Choose, edit, edit_dtd, edit_encoding, pick
from .h3d_inputs import crafted_h3d, mutate_h3d
from .seeds import TINY_ASF, mit_sequence, mit_tree, write_mit
from .sidecars import SIDECARS, crafted_sidecar, mutate_sidecar

FORMATS = ("mmm", "asf", "amc", "bvh", "mit", "h3d") + SIDECARS


# ------------------------------------------------------------------------ mutations
def mutate(data: bytes, choose: Choose, fmt: str = "") -> bytes:
    """``data`` with 1-3 random edits (XML, ``fmt="mmm"``, also gets encodings and DTDs;
    ``fmt="h3d"``: edits of the files of the folder it packs)."""
    if fmt == "h3d":
        return mutate_h3d(data, choose)
    if fmt in SIDECARS:
        return mutate_sidecar(data, choose, fmt)
    ops = ["truncate", "flip", "delete", "duplicate", "swap", "number", "number", "token",
           "garbage", "repeat"] + (["encoding", "dtd", "dtd"] if fmt == "mmm" else []) \
        + (["mat-tag"] * 4 if fmt == "mit" else [])
    for _ in range(1 + choose(3)):
        data = edit(data, pick(choose, ops), choose)
    return data


# ------------------------------------------------------------------------ crafted files
def _order(n: int, choose: Choose) -> list[int]:
    """0..n-1 as listed: in order (parents first), reversed (children first) or strided."""
    how = choose(3)
    if how == 2:
        step = 2 + choose(6)
        return [i for r in range(step) for i in range(r, n, step)][::-1 if choose(2) else 1]
    return list(range(n))[::-1 if how else 1]


def _asf(choose: Choose):
    n = pick(choose, [1, 3, 40, 400, 1990, 2500, 16000])
    shape = choose(3)  # a chain (deep), a star (wide) or a random tree
    parent = [i - 1 if shape == 0 else -1 if shape == 1 else choose(i + 1) - 1 for i in range(n)]
    if n > 1 and choose(6) == 0:
        parent[0] = n - 1  # a cycle through the first bone
    direction = pick(choose, [b"0 1 0", b"1 0 0", b"0 0 0", b"1e300 0 0", b"nan 0 0"])
    length = pick(choose, [b"1", b"0", b"1e12", b"-3", b"9" * 500])
    dof = pick(choose, [b"rx ry rz", b"rz", b"", b"rx rx", b"tx"])
    bones = [b"begin\nname b%d\ndirection %s\nlength %s\naxis 0 0 %d XYZ\n%s\nend" % (
        i, direction, length, i % 360, b"dof " + dof if dof else b"") for i in _order(n, choose)]
    kids: dict[int, list[int]] = {}
    for i in _order(n, choose):
        kids.setdefault(parent[i], []).append(i)
    hier = [(b"root" if p < 0 else b"b%d" % p) + b"".join(b" b%d" % c for c in cs)
            for p, cs in kids.items()]
    units = pick(choose, [b"length 0.45\nangle deg", b"angle rad", b"length 0", b"length 1e-320"])
    return (b":units\n%s\n:root\norder TX TY TZ RX RY RZ\naxis XYZ\n:bonedata\n%s\n"
            b":hierarchy\nbegin\n%s\nend\n" % (units, b"\n".join(bones), b"\n".join(hier))), None


def _bvh(choose: Choose):
    n = pick(choose, [1, 4, 60, 1990, 5000])
    deep = choose(2)
    chans = pick(choose, [b"0", b"3 Zrotation Xrotation Yrotation",
                           b"6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"])
    offset = pick(choose, [b"0 1 0", b"0 0 0", b"1e11 0 0", b"0 -1e12 0"])
    root = pick(choose, [b"6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                          b"1 Xrotation"])
    head = [b"HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS %s" % root]
    for i in range(1, n):
        head.append(b"JOINT j%d\n{\nOFFSET %s\nCHANNELS %s%s" % (
            i, offset, chans, b"" if deep else b"\nEnd Site\n{\nOFFSET 0 1 0\n}\n}"))
    head.append(b"End Site\n{\nOFFSET 0 1 0\n}\n" + b"}\n" * (n if deep else 1))
    C = int(root.split()[0]) + (n - 1) * int(chans.split()[0])
    declared = pick(choose, [1, 3, 1000, 10 ** 6, 10 ** 12, 2 ** 63, 0, -5])
    given = max(1, min(declared, pick(choose, [1, 3, 50, 10 ** 6])))
    if given * C > 2_000_000:  # every frame it declares only where that stays small
        given = min(declared, 50)
    value = pick(choose, [b"0", b"1.5", b"90", b"-45", b"1e11"] + SPECIAL[:8])
    frames = (b" ".join([value] * C) + b"\n") * given
    return b"\n".join(head) + b"MOTION\nFrames: %d\nFrame Time: 0.0083333\n" % declared \
        + frames, None


def _amc(choose: Choose):
    frames = pick(choose, [1, 3, 1000, 20000])
    odd = pick(choose, [b"9" * 5000, "²".encode(), b"%d" % 10 ** 15, b"-1", b"+1"])
    number = pick(choose, [lambda i: b"%d" % (i + 1), lambda i: odd if i == frames - 1
                            else b"%d" % (i + 1), lambda i: b"%d" % (10 ** 15 + i)])
    value = pick(choose, [b"0", b"1.5", b"-720", b"1e13", b"nan", b"9" * 400])
    body = b"".join(b"%s\nroot 0 0 0 %s 0 0\nchest 1 2 3\nlarm %s\nrarm 4\n"
                    % (number(i), value, value) for i in range(frames))
    if choose(4) == 0:
        body = body.replace(b"rarm 4\n", b"", 1)  # a frame without a bone
    return b":FULLY-SPECIFIED\n:DEGREES\n" + body, TINY_ASF


def _mmm(choose: Choose):
    from motionlang.formats.mmm_model import MMM_DOF_ORDER
    frames = pick(choose, [1, 3, 2000])
    joints = list(MMM_DOF_ORDER[:pick(choose, [0, 2, 44])]) + (["Bogus_joint"] * choose(2))
    step = pick(choose, [b"0.01", b"0", b"-0.01", b"1e-320", b"1e300"])
    value = pick(choose, [b"0", b"0.5", b"-3.1", b"1e300"] + SPECIAL[:8])
    frame = (b"<MotionFrame><Timestep>%s</Timestep><RootPosition>0 0 900</RootPosition>"
             b"<RootRotation>0 0 0</RootRotation><JointPosition>" + b" ".join(
                 [value] * len(joints)) + b"</JointPosition></MotionFrame>\n")
    body = b"".join(frame % (b"%.2f" % (i / 100) if step == b"0.01" else step)
                    for i in range(frames))
    data = (b"<?xml version='1.0'?>\n<MMM><Motion name='x'><JointOrder>" + b"".join(
        b"<Joint name='%s'/>" % j.encode() for j in joints) + b"</JointOrder><MotionFrames>\n"
        + body + b"</MotionFrames></Motion></MMM>\n")
    how = choose(3)
    if how == 1:
        data = edit_encoding(data, choose)
    elif how == 2:
        data = edit_dtd(data, choose)
    return data, None


_BAD_FIELDS = [lambda: "text", lambda: np.array([[np.nan, 1, 2]]), lambda: {"x": np.ones(3)},
               lambda: np.array([[1 + 2j, 2, 3]]), lambda: np.array([[1, 2, 3]], np.int8),
               lambda: np.array([[1e300, 2, 3]]), lambda: np.zeros((0, 0)),
               lambda: np.array([[0.5, 1, 2]]), lambda: np.array([[1.0, 2, 3, 4]]),
               lambda: np.array([[True, False, True]]), lambda: np.array([[1e18, 2, 3]])]


def _mit(choose: Choose):
    n = pick(choose, [1, 2, 18, 300, 2100])
    tree = mit_tree(n)
    for _ in range(choose(4)):
        field = pick(choose, ["parent", "or", "offset", "children"])
        if choose(5) == 0:
            for node in tree:
                node.pop(field, None)  # a field missing from every node
        else:
            cell = np.empty((1, 1), dtype=object)
            cell[0, 0] = np.ones((1, 3))
            bad = _BAD_FIELDS + [lambda cell=cell: cell]
            tree[choose(n)][field] = pick(choose, bad)()
    T = pick(choose, [1, 3, 40])
    seq = pick(choose, [lambda: mit_sequence(T, n), lambda: "abc",
                         lambda: mit_sequence(T, n)[:, :-1], lambda: np.zeros((0, 6 * n)),
                         lambda: mit_sequence(T, n).astype(np.int16),
                         lambda: mit_sequence(T, n) * 1e300, lambda: {"a": 1.0},
                         lambda: mit_sequence(T, n) + 1j])()
    motion = [seq, mit_sequence(2, n)][:1 + choose(2)]
    if choose(8) == 0:
        motion = pick(choose, ["Motion", np.ones((3, 6 * n))])  # not a cell at all
    return write_mit(tree, motion, compress=bool(choose(2))), None


def crafted(fmt: str, choose: Choose) -> tuple[bytes, bytes | None]:
    """A file crafted to stress the ``fmt`` reader, and the ASF an AMC is read with."""
    if fmt in SIDECARS:
        return crafted_sidecar(fmt, choose), None
    return {"asf": _asf, "amc": _amc, "bvh": _bvh, "mmm": _mmm, "mit": _mit,
            "h3d": crafted_h3d}[fmt](choose)


__all__ = ["FORMATS", "SPECIAL", "mutate", "crafted"]

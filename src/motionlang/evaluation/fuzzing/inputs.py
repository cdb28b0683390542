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
"""
from __future__ import annotations

import io
import re
from typing import Callable

import numpy as np

from motionlang.evaluation.fuzzing.seeds import (TINY_ASF, h3d_files, mit_sequence,
                                              mit_tree, npy_bytes, pack_h3d, unpack_h3d,
                                              write_mit)

FORMATS = ("mmm", "asf", "amc", "bvh", "mit", "h3d")
Choose = Callable[[int], int]
MAX_GROWTH = 4 << 20  # a file this long is not lengthened further

SPECIAL = [b"1e308", b"-1e308", b"nan", b"NaN", b"inf", b"-inf", b"1e999", b"", b"0x10",
           b"1e-400", b"123456789012345678901234567890", b"1.5.5", b"-", b"{", b"}",
           b"9" * 400, b"9" * 5000, "²".encode(), "١٢".encode(), b"1_000", b"+5", b"-0",
           b"9223372036854775808", b"1e12", b"1e13", b"4e-324"]
ENCODINGS = [b"utf-32", b"UTF-16", b"utf-16-le", b"utf-8", b"latin-1", b"klingon", b"ascii",
             b"shift_jis", b"cp037", b"utf-7", b"", b"x" * 300]
LAUGHS = (b'<!DOCTYPE MMM [<!ENTITY a "aaaaaaaaaa">' + b"".join(
    b'<!ENTITY %s "%s">' % (bytes([98 + i]), b"&%s;" % bytes([97 + i]) * 10) for i in range(8))
    + b"]>")
DTDS = [LAUGHS, b'<!DOCTYPE MMM [<!ENTITY q "' + b"1 " * 20000 + b'">]>',
        b'<!DOCTYPE MMM [<!ENTITY e SYSTEM "file:///etc/passwd">]>',
        b'<!DOCTYPE MMM [<!ENTITY % p SYSTEM "http://127.0.0.1:9/x.dtd"> %p;]>',
        b'<!DOCTYPE MMM SYSTEM "http://127.0.0.1:9/mmm.dtd">',
        b'<!DOCTYPE MMM [<!ENTITY e "0.5">]>']
ENTITY_REFS = [b"&i;", b"&q;", b"&e;", b"&a;", b"&amp;", b"&#0;", b"&#x110000;"]
NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
TOKEN = re.compile(rb"[^\s<>=']+")
_DECL = re.compile(rb"^\s*<\?xml[^>]*\?>")


def _pick(choose: Choose, seq):
    return seq[choose(len(seq))]


# ------------------------------------------------------------------------ mutations
def mutate(data: bytes, choose: Choose, fmt: str = "") -> bytes:
    """``data`` with 1-3 random edits (XML, ``fmt="mmm"``, also gets encodings and DTDs;
    ``fmt="h3d"``: edits of the files of the folder it packs)."""
    if fmt == "h3d":
        return _mutate_h3d(data, choose)
    ops = ["truncate", "flip", "delete", "duplicate", "swap", "number", "number", "token",
           "garbage", "repeat"] + (["encoding", "dtd", "dtd"] if fmt == "mmm" else []) \
        + (["mat-tag"] * 4 if fmt == "mit" else [])
    for _ in range(1 + choose(3)):
        data = _edit(data, _pick(choose, ops), choose)
    return data


def _edit(data: bytes, op: str, choose: Choose) -> bytes:
    if op == "truncate":
        return data[:choose(len(data) + 1)]
    if op == "flip" and data:
        i = choose(len(data))
        return data[:i] + bytes([choose(256)]) + data[i + 1:]
    if op in ("delete", "duplicate", "swap", "repeat"):
        lines = data.split(b"\n")
        i = choose(len(lines))
        if op == "delete":
            del lines[i]
        elif op == "duplicate":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = choose(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
        elif len(data) < MAX_GROWTH:  # a block of lines repeated: long inputs
            lines[i:i] = lines[i:i + 1 + choose(20)] * _pick(choose, [2, 10, 100, 2000])
        return b"\n".join(lines)
    if op in ("number", "token"):
        spans = [m.span() for m in (NUMBER if op == "number" else TOKEN).finditer(data)]
        if not spans:
            return data
        a, b = spans[choose(len(spans))]
        c, d = spans[choose(len(spans))]
        return data[:a] + (_pick(choose, SPECIAL) if op == "number" else data[c:d]) + data[b:]
    if op == "garbage":
        i = choose(len(data) + 1)
        return data[:i] + bytes(choose(256) for _ in range(choose(25))) + data[i:]
    if op == "mat-tag":
        return _mat_tag(data, choose)
    if op == "encoding":
        return _encoding(data, choose)
    if op == "dtd":
        return _dtd(data, choose)
    return data


def _mat_tag(data: bytes, choose: Choose) -> bytes:
    """A MAT element tag (8-byte aligned after the 128-byte header) with another type or
    size: an uncompressed file's structure, where a flipped byte rarely lands."""
    if len(data) < 136:
        return data
    i = 128 + 8 * choose((len(data) - 128) // 8)
    if choose(2):
        value = choose(20)
    else:
        old = int.from_bytes(data[i + 4:i + 8], "little")
        value = _pick(choose, [0, 1, 7, 8, 2 ** 31, 2 ** 32 - 1, old + 8, max(old - 8, 0)])
        i += 4
    return data[:i] + value.to_bytes(4, "little") + data[i + 4:]


def _encoding(data: bytes, choose: Choose) -> bytes:
    """Declare an encoding; or write the text in another one, declared or not."""
    body = _DECL.sub(b"", data, count=1)
    decl = b"<?xml version='1.0' encoding='%s'?>" % _pick(choose, ENCODINGS)
    how = choose(3)
    if how == 0:
        return decl + body
    codec = _pick(choose, ["utf-16", "utf-32", "utf-16-be", "latin-1"])
    text = ((decl if how == 1 else b"") + body).decode("utf-8", errors="replace")
    return text.encode(codec, errors="replace")


def _dtd(data: bytes, choose: Choose) -> bytes:
    """Insert a DTD after the XML declaration, maybe with an entity where a number was."""
    m = _DECL.match(data)
    at = m.end() if m else 0
    dtd = _pick(choose, DTDS)
    out = data[:at] + dtd + data[at:]
    spans = [s.span() for s in NUMBER.finditer(out, at + len(dtd))]
    if spans and choose(2):
        a, b = spans[choose(len(spans))]
        out = out[:a] + _pick(choose, ENTITY_REFS) + out[b:]
    return out


# ------------------------------------------------------------------------ crafted files
def _order(n: int, choose: Choose) -> list[int]:
    """0..n-1 as listed: in order (parents first), reversed (children first) or strided."""
    how = choose(3)
    if how == 2:
        step = 2 + choose(6)
        return [i for r in range(step) for i in range(r, n, step)][::-1 if choose(2) else 1]
    return list(range(n))[::-1 if how else 1]


def _asf(choose: Choose):
    n = _pick(choose, [1, 3, 40, 400, 1990, 2500, 16000])
    shape = choose(3)  # a chain (deep), a star (wide) or a random tree
    parent = [i - 1 if shape == 0 else -1 if shape == 1 else choose(i + 1) - 1 for i in range(n)]
    if n > 1 and choose(6) == 0:
        parent[0] = n - 1  # a cycle through the first bone
    direction = _pick(choose, [b"0 1 0", b"1 0 0", b"0 0 0", b"1e300 0 0", b"nan 0 0"])
    length = _pick(choose, [b"1", b"0", b"1e12", b"-3", b"9" * 500])
    dof = _pick(choose, [b"rx ry rz", b"rz", b"", b"rx rx", b"tx"])
    bones = [b"begin\nname b%d\ndirection %s\nlength %s\naxis 0 0 %d XYZ\n%s\nend" % (
        i, direction, length, i % 360, b"dof " + dof if dof else b"") for i in _order(n, choose)]
    kids: dict[int, list[int]] = {}
    for i in _order(n, choose):
        kids.setdefault(parent[i], []).append(i)
    hier = [(b"root" if p < 0 else b"b%d" % p) + b"".join(b" b%d" % c for c in cs)
            for p, cs in kids.items()]
    units = _pick(choose, [b"length 0.45\nangle deg", b"angle rad", b"length 0", b"length 1e-320"])
    return (b":units\n%s\n:root\norder TX TY TZ RX RY RZ\naxis XYZ\n:bonedata\n%s\n"
            b":hierarchy\nbegin\n%s\nend\n" % (units, b"\n".join(bones), b"\n".join(hier))), None


def _bvh(choose: Choose):
    n = _pick(choose, [1, 4, 60, 1990, 5000])
    deep = choose(2)
    chans = _pick(choose, [b"0", b"3 Zrotation Xrotation Yrotation",
                           b"6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"])
    offset = _pick(choose, [b"0 1 0", b"0 0 0", b"1e11 0 0", b"0 -1e12 0"])
    root = _pick(choose, [b"6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                          b"1 Xrotation"])
    head = [b"HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS %s" % root]
    for i in range(1, n):
        head.append(b"JOINT j%d\n{\nOFFSET %s\nCHANNELS %s%s" % (
            i, offset, chans, b"" if deep else b"\nEnd Site\n{\nOFFSET 0 1 0\n}\n}"))
    head.append(b"End Site\n{\nOFFSET 0 1 0\n}\n" + b"}\n" * (n if deep else 1))
    C = int(root.split()[0]) + (n - 1) * int(chans.split()[0])
    declared = _pick(choose, [1, 3, 1000, 10 ** 6, 10 ** 12, 2 ** 63, 0, -5])
    given = max(1, min(declared, _pick(choose, [1, 3, 50, 10 ** 6])))
    if given * C > 2_000_000:  # every frame it declares only where that stays small
        given = min(declared, 50)
    value = _pick(choose, [b"0", b"1.5", b"90", b"-45", b"1e11"] + SPECIAL[:8])
    frames = (b" ".join([value] * C) + b"\n") * given
    return b"\n".join(head) + b"MOTION\nFrames: %d\nFrame Time: 0.0083333\n" % declared \
        + frames, None


def _amc(choose: Choose):
    frames = _pick(choose, [1, 3, 1000, 20000])
    odd = _pick(choose, [b"9" * 5000, "²".encode(), b"%d" % 10 ** 15, b"-1", b"+1"])
    number = _pick(choose, [lambda i: b"%d" % (i + 1), lambda i: odd if i == frames - 1
                            else b"%d" % (i + 1), lambda i: b"%d" % (10 ** 15 + i)])
    value = _pick(choose, [b"0", b"1.5", b"-720", b"1e13", b"nan", b"9" * 400])
    body = b"".join(b"%s\nroot 0 0 0 %s 0 0\nchest 1 2 3\nlarm %s\nrarm 4\n"
                    % (number(i), value, value) for i in range(frames))
    if choose(4) == 0:
        body = body.replace(b"rarm 4\n", b"", 1)  # a frame without a bone
    return b":FULLY-SPECIFIED\n:DEGREES\n" + body, TINY_ASF


def _mmm(choose: Choose):
    from motionlang.formats.mmm_model import MMM_DOF_ORDER
    frames = _pick(choose, [1, 3, 2000])
    joints = list(MMM_DOF_ORDER[:_pick(choose, [0, 2, 44])]) + (["Bogus_joint"] * choose(2))
    step = _pick(choose, [b"0.01", b"0", b"-0.01", b"1e-320", b"1e300"])
    value = _pick(choose, [b"0", b"0.5", b"-3.1", b"1e300"] + SPECIAL[:8])
    frame = (b"<MotionFrame><Timestep>%s</Timestep><RootPosition>0 0 900</RootPosition>"
             b"<RootRotation>0 0 0</RootRotation><JointPosition>" + b" ".join(
                 [value] * len(joints)) + b"</JointPosition></MotionFrame>\n")
    body = b"".join(frame % (b"%.2f" % (i / 100) if step == b"0.01" else step)
                    for i in range(frames))
    data = (b"<?xml version='1.0'?>\n<MMM><Motion name='x'><JointOrder>" + b"".join(
        b"<Joint name='%s'/>" % j.encode() for j in joints) + b"</JointOrder><MotionFrames>\n"
        + body + b"</MotionFrames></Motion></MMM>\n")
    how = choose(3)
    return (_encoding(data, choose) if how == 1 else _dtd(data, choose) if how == 2 else data), None


_BAD_FIELDS = [lambda: "text", lambda: np.array([[np.nan, 1, 2]]), lambda: {"x": np.ones(3)},
               lambda: np.array([[1 + 2j, 2, 3]]), lambda: np.array([[1, 2, 3]], np.int8),
               lambda: np.array([[1e300, 2, 3]]), lambda: np.zeros((0, 0)),
               lambda: np.array([[0.5, 1, 2]]), lambda: np.array([[1.0, 2, 3, 4]]),
               lambda: np.array([[True, False, True]]), lambda: np.array([[1e18, 2, 3]])]


def _mit(choose: Choose):
    n = _pick(choose, [1, 2, 18, 300, 2100])
    tree = mit_tree(n)
    for _ in range(choose(4)):
        field = _pick(choose, ["parent", "or", "offset", "children"])
        if choose(5) == 0:
            for node in tree:
                node.pop(field, None)  # a field missing from every node
        else:
            cell = np.empty((1, 1), dtype=object)
            cell[0, 0] = np.ones((1, 3))
            bad = _BAD_FIELDS + [lambda: cell]
            tree[choose(n)][field] = _pick(choose, bad)()
    T = _pick(choose, [1, 3, 40])
    seq = _pick(choose, [lambda: mit_sequence(T, n), lambda: "abc",
                         lambda: mit_sequence(T, n)[:, :-1], lambda: np.zeros((0, 6 * n)),
                         lambda: mit_sequence(T, n).astype(np.int16),
                         lambda: mit_sequence(T, n) * 1e300, lambda: {"a": 1.0},
                         lambda: mit_sequence(T, n) + 1j])()
    motion = [seq, mit_sequence(2, n)][:1 + choose(2)]
    if choose(8) == 0:
        motion = _pick(choose, ["Motion", np.ones((3, 6 * n))])  # not a cell at all
    return write_mit(tree, motion, compress=bool(choose(2))), None


# ------------------------------------------------------------------ HumanML3D layout
NPY_DESCRS = [b"'|O'", b"'<c16'", b"'<U3'", b"'|S4'", b"'>f8'", b"'<f2'", b"'<i8'", b"'|b1'",
              b"[('a', '<f4')]", b"'<M8[s]'", b"'V4'", b"'<f4', (3,)", b"'x'", b"''",
              b"'<f4'", b"'|u1'"]
NPY_SHAPES = [b"()", b"(0,)", b"(0, 251)", b"(0, 263)", b"(1, 251)", b"(3, 263)", b"(5,)",
              b"(2, 21, 3)", b"(2, 22, 3)", b"(3, 21)", b"(1000000000000, 251)",
              b"(4611686018427387904, 263)", b"(-1, 251)", b"(2, 251, 1)", b"(2, 0)",
              b"(" + b"1, " * 36 + b"1)", b"(2.5, 251)", b"('a', 251)", b"(10000, 21, 3)"]
CAPTION_LINES = [b"a person walks#a/DET#0.0#0.0", b"no tokens", b"#", b"##", b"###", b"####",
                 b"a#b#c#d#e#f#g", b"walks#w#1.0", b"walks#w#2.0#1.0", b"walks#w#-1#2",
                 b"walks#w#inf#inf", b"walks#w#nan#3", b"walks#w#1e308#1e309",
                 b"walks#w#0#1e300", b"walks#w#soon#later", b"walks#w#0x10#2",
                 b"walks#w#\xff\xfe#1", b"walks#w#0.1#0.1", b"walks#w#100#200",
                 b"\xff\xfe\x00w", "\u00e9l\u00e8ve marche#\u00e9/X#0#0".encode("latin-1"),
                 b"x" * 200_000 + b"#t#0#0", b"walks#" + b"w/X " * 50_000 + b"#0#0",
                 b"\x00\x00\x00", b"\r\r\r", "walks#w#\u0661#\u0662".encode(), b"  #  #  #  "]
SPLIT_LINES = [b"../x", b"/etc/passwd", b"missing", b"000001", b"M000001", b"../../../tmp/a",
               b"\xff\xfe", b"a" * 100_000, b"", b"\x00", b"new_joints/000001", b"~", b"."]


def _npy_header(data: bytes, choose: Choose) -> bytes:
    """An ``.npy`` header with another dtype, shape or order (the length fields kept)."""
    end = data.find(b"\n")
    if not data.startswith(b"\x93NUMPY") or end < 0:
        return data
    head = data[:end]
    what = choose(5)
    if what == 0:
        head = re.sub(rb"'descr': [^,]+(?:, \([^)]*\))?", b"'descr': " + _pick(choose, NPY_DESCRS),
                      head, count=1)
    elif what == 1:
        head = re.sub(rb"'shape': \([^)]*\)", b"'shape': " + _pick(choose, NPY_SHAPES), head,
                      count=1)
    elif what == 2:
        head = head.replace(b"False", b"True") if choose(2) else head.replace(b"False", b"1")
    elif what == 3:  # the version or the header length
        i = _pick(choose, [6, 7, 8, 9])
        head = head[:i] + bytes([_pick(choose, [0, 1, 2, 3, 255, 0x7f])]) + head[i + 1:]
    else:
        head = head[:choose(len(head) + 1)]
    if what in (0, 1) and head[:8] == b"\x93NUMPY\x01\x00" and choose(4):
        rest = head[10:]  # the header length kept consistent, as a writer would
        rest += b" " * ((-(10 + len(rest) + 1)) % 64)
        head = head[:8] + (len(rest) + 1).to_bytes(2, "little") + rest
    return head + data[end:]


def _npy_data(data: bytes, choose: Choose) -> bytes:
    """An ``.npy`` file's numbers with NaN, inf or huge values in places, or cut short."""
    end = data.find(b"\n") + 1
    if end <= 0 or len(data) <= end:
        return data
    how = choose(3)
    if how == 0:
        return data[:end + choose(len(data) - end)]
    if b"<f4" not in data[:end]:
        return data
    values = np.frombuffer(data[end:len(data) - (len(data) - end) % 4], "<f4").copy()
    bad = _pick(choose, [np.nan, np.inf, -np.inf, 3e38, -3e38, 1e20, 0.0])
    if how == 1:
        values[choose(len(values))] = bad
    else:
        values[choose(len(values)):] = bad
    return data[:end] + values.tobytes()


def _h3d_edit(files: dict[str, bytes], choose: Choose, body: str) -> None:
    names = sorted(files)
    op = choose(10)
    if not names or op == 0:  # a file added or replaced by one of the other body or shape
        T = _pick(choose, [1, 2, 3, 40])
        other = h3d_files(_pick(choose, ["kit", "smpl"]), T + 1, ("000001",))
        name = _pick(choose, sorted(other))
        files[_pick(choose, [name, name.replace("000001", "000002"),
                             name.replace("000001", "M000002")])] = other[name]
        return
    name = _pick(choose, names)
    data = files[name]
    if op == 1:
        del files[name]
    elif op == 2:
        files[name] = b""
    elif op in (3, 4) and name.endswith(".npy"):
        files[name] = _npy_header(data, choose)
    elif op == 5 and name.endswith(".npy"):
        files[name] = _npy_data(data, choose)
    elif op in (6, 7) and name.endswith(".txt"):
        pool = SPLIT_LINES if "/" not in name else CAPTION_LINES
        lines = data.split(b"\n")
        lines.insert(choose(len(lines) + 1), _pick(choose, pool))
        files[name] = b"\n".join(lines)
    elif op == 8 and name.endswith(".txt"):
        codec = _pick(choose, ["utf-16", "utf-32", "latin-1", "cp037"])
        files[name] = data.decode("utf-8", "replace").encode(codec, "replace")
    else:
        files[name] = _edit(data, _pick(choose, ["truncate", "flip", "delete", "duplicate",
                                                  "swap", "number", "token", "garbage",
                                                  "repeat"]), choose)


def _mutate_h3d(data: bytes, choose: Choose) -> bytes:
    body, files = unpack_h3d(data)
    for _ in range(1 + choose(3)):
        _h3d_edit(files, choose, body)
    return pack_h3d(files, body)


def _h3d(choose: Choose):
    body = _pick(choose, ["kit", "smpl"])
    from motionlang.features.h3d_vectors import H3D_BODIES
    spec = H3D_BODIES[body]
    T = _pick(choose, [1, 2, 3, 30, 2000])
    captions = b"\n".join(_pick(choose, CAPTION_LINES) for _ in range(1 + choose(4)))
    files = h3d_files(body, T + 1, ("000001",), captions)
    what = choose(6)
    target = _pick(choose, ["new_joint_vecs/000001.npy", "new_joints/000001.npy"])
    if what == 0:  # another dtype, shape or values
        shape = (T, spec.dim) if target.startswith("new_joint_vecs") else (T, spec.n_joints, 3)
        make = _pick(choose, [
            lambda: np.full(shape, np.nan, np.float32), lambda: np.zeros(shape, np.float16),
            lambda: np.ones(shape, np.int64), lambda: np.zeros(shape, np.complex64),
            lambda: np.array([["x"] * 3] * 2), lambda: np.empty((2, 3), dtype=object),
            lambda: np.zeros((0,) + shape[1:], np.float32), lambda: np.zeros(shape[::-1]),
            lambda: np.full(shape, 1e30, np.float32), lambda: np.zeros((2, 7), np.float32),
            lambda: np.zeros(shape, [("a", "<f4")]), lambda: np.float32(3.0),
            lambda: np.zeros(shape, ">f8"), lambda: np.asfortranarray(np.zeros(shape))])
        files[target] = npy_bytes(make())
    elif what == 1:  # a huge declared shape over a few bytes
        head = {"descr": "<f4", "fortran_order": False,
                "shape": (_pick(choose, [10 ** 7, 10 ** 9, 2 ** 40, 2 ** 62]), spec.dim)}
        buf = io.BytesIO()
        np.lib.format.write_array_header_1_0(buf, head)
        files[target] = buf.getvalue() + b"\0" * _pick(choose, [0, 8, 4096])
    elif what == 2:
        files.pop(target)
        if choose(2):
            files.pop("new_joints/000001.npy", None)
    elif what == 3:
        files[_pick(choose, ["train.txt", "val.txt", "test.txt"])] = b"\n".join(
            _pick(choose, SPLIT_LINES) for _ in range(1 + choose(5)))
    elif what == 4:
        files[target] = _npy_header(files[target], choose)
    return pack_h3d(files, body), None


def crafted(fmt: str, choose: Choose) -> tuple[bytes, bytes | None]:
    """A file crafted to stress the ``fmt`` reader, and the ASF an AMC is read with."""
    return {"asf": _asf, "amc": _amc, "bvh": _bvh, "mmm": _mmm, "mit": _mit,
            "h3d": _h3d}[fmt](choose)


__all__ = ["FORMATS", "SPECIAL", "mutate", "crafted"]

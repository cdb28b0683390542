"""Fuzzing inputs in the HumanML3D layout (``h3d``: a folder packed as one tar, see
:func:`.seeds.pack_h3d`): ``.npy`` headers that are corrupt, truncated, declare other or
huge shapes or object/complex/text dtypes; data holding NaN or inf; caption lines with odd
``#`` counts, broken, reversed or negative time spans, other encodings or very long lines;
split files naming missing ids or paths (``../x``, ``/etc/passwd``); files missing,
emptied or added.
"""
from __future__ import annotations

import io
import re

import numpy as np

from .edits import Choose, edit, pick
from .seeds import h3d_files, npy_bytes, pack_h3d, unpack_h3d

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


def edit_npy_header(data: bytes, choose: Choose) -> bytes:
    """An ``.npy`` header with another dtype, shape or order (the length fields kept)."""
    end = data.find(b"\n")
    if not data.startswith(b"\x93NUMPY") or end < 0:
        return data
    head = data[:end]
    what = choose(5)
    if what == 0:
        head = re.sub(rb"'descr': [^,]+(?:, \([^)]*\))?", b"'descr': " + pick(choose, NPY_DESCRS),
                      head, count=1)
    elif what == 1:
        head = re.sub(rb"'shape': \([^)]*\)", b"'shape': " + pick(choose, NPY_SHAPES), head,
                      count=1)
    elif what == 2:
        head = head.replace(b"False", b"True") if choose(2) else head.replace(b"False", b"1")
    elif what == 3:  # the version or the header length
        i = pick(choose, [6, 7, 8, 9])
        head = head[:i] + bytes([pick(choose, [0, 1, 2, 3, 255, 0x7f])]) + head[i + 1:]
    else:
        head = head[:choose(len(head) + 1)]
    if what in (0, 1) and head[:8] == b"\x93NUMPY\x01\x00" and choose(4):
        rest = head[10:]  # the header length kept consistent, as a writer would
        rest += b" " * ((-(10 + len(rest) + 1)) % 64)
        head = head[:8] + (len(rest) + 1).to_bytes(2, "little") + rest
    return head + data[end:]


def edit_npy_data(data: bytes, choose: Choose) -> bytes:
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
    bad = pick(choose, [np.nan, np.inf, -np.inf, 3e38, -3e38, 1e20, 0.0])
    if how == 1:
        values[choose(len(values))] = bad
    else:
        values[choose(len(values)):] = bad
    return data[:end] + values.tobytes()


def _h3d_edit(files: dict[str, bytes], choose: Choose, body: str) -> None:
    names = sorted(files)
    op = choose(10)
    if not names or op == 0:  # a file added or replaced by one of the other body or shape
        T = pick(choose, [1, 2, 3, 40])
        other = h3d_files(pick(choose, ["kit", "smpl"]), T + 1, ("000001",))
        name = pick(choose, sorted(other))
        files[pick(choose, [name, name.replace("000001", "000002"),
                             name.replace("000001", "M000002")])] = other[name]
        return
    name = pick(choose, names)
    data = files[name]
    if op == 1:
        del files[name]
    elif op == 2:
        files[name] = b""
    elif op in (3, 4) and name.endswith(".npy"):
        files[name] = edit_npy_header(data, choose)
    elif op == 5 and name.endswith(".npy"):
        files[name] = edit_npy_data(data, choose)
    elif op in (6, 7) and name.endswith(".txt"):
        pool = SPLIT_LINES if "/" not in name else CAPTION_LINES
        lines = data.split(b"\n")
        lines.insert(choose(len(lines) + 1), pick(choose, pool))
        files[name] = b"\n".join(lines)
    elif op == 8 and name.endswith(".txt"):
        codec = pick(choose, ["utf-16", "utf-32", "latin-1", "cp037"])
        files[name] = data.decode("utf-8", "replace").encode(codec, "replace")
    else:
        files[name] = edit(data, pick(choose, ["truncate", "flip", "delete", "duplicate",
                                                  "swap", "number", "token", "garbage",
                                                  "repeat"]), choose)


def mutate_h3d(data: bytes, choose: Choose) -> bytes:
    body, files = unpack_h3d(data)
    for _ in range(1 + choose(3)):
        _h3d_edit(files, choose, body)
    return pack_h3d(files, body)


def crafted_h3d(choose: Choose):
    body = pick(choose, ["kit", "smpl"])
    from motionlang.features.h3d_vectors import H3D_BODIES
    spec = H3D_BODIES[body]
    T = pick(choose, [1, 2, 3, 30, 2000])
    captions = b"\n".join(pick(choose, CAPTION_LINES) for _ in range(1 + choose(4)))
    files = h3d_files(body, T + 1, ("000001",), captions)
    what = choose(6)
    target = pick(choose, ["new_joint_vecs/000001.npy", "new_joints/000001.npy"])
    if what == 0:  # another dtype, shape or values
        shape = (T, spec.dim) if target.startswith("new_joint_vecs") else (T, spec.n_joints, 3)
        make = pick(choose, [
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
                "shape": (pick(choose, [10 ** 7, 10 ** 9, 2 ** 40, 2 ** 62]), spec.dim)}
        buf = io.BytesIO()
        np.lib.format.write_array_header_1_0(buf, head)
        files[target] = buf.getvalue() + b"\0" * pick(choose, [0, 8, 4096])
    elif what == 2:
        files.pop(target)
        if choose(2):
            files.pop("new_joints/000001.npy", None)
    elif what == 3:
        files[pick(choose, ["train.txt", "val.txt", "test.txt"])] = b"\n".join(
            pick(choose, SPLIT_LINES) for _ in range(1 + choose(5)))
    elif what == 4:
        files[target] = edit_npy_header(files[target], choose)
    return pack_h3d(files, body), None

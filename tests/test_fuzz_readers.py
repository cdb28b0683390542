"""Fuzzing every reader, each input read in a child process under a memory cap (RLIMIT_AS)
and a time limit (``benchmarks/fuzzing/``): the only acceptable outcomes are a
``MotionlangError`` whose message is one line naming the file, or a valid Motion (finite
arrays, consistent shapes, finite joint positions); never a crash, a hang, an uncaught
exception.

Per format (MMM XML, ASF, AMC, BVH, MIT ``.mat``, H3D: a HumanML3D-layout folder packed as a
tar): edits of seeds (hand-made files and real ones cut to a few frames) and files crafted
against that reader (encodings and DTDs, deep and wide skeletons, child-first bone lists,
huge numbers and frame counts, MAT fields of the wrong type, long inputs; ``.npy`` headers
with object dtypes or huge shapes, NaN rows, broken caption spans, odd split files).
Hypothesis runs derandomized (reproducible in CI). The findings of the fuzzing issue are
pinned as explicit examples. ``benchmarks/fuzz_readers.py`` runs the same at 10,000 inputs
per format.
"""
from __future__ import annotations

import io
import os
import signal
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers.data import ROOT, SHARED

sys.path.insert(0, str(ROOT / "benchmarks"))  # the fuzzing package lives beside its benchmark
from fuzzing import FORMATS, Sandbox, crafted, mutate, seeds  # noqa: E402
from fuzzing.seeds import (  # noqa: E402
    TINY_ASF,
    h3d_files,
    mit_sequence,
    mit_tree,
    npy_bytes,
    pack_h3d,
    write_mit,
)
from fuzzing.sidecars import SIDECARS, sidecar_seeds  # noqa: E402

pytest.importorskip("resource")  # the sandbox needs Unix
MUTATED, CRAFTED = 150, 60  # inputs per motion format: 210, a couple of minutes in all
SIDE_MUTATED, SIDE_CRAFTED = 20, 10  # per sidecar format (captions, models, indexes, GLB)
MOTION_FORMATS = tuple(f for f in FORMATS if f not in SIDECARS)
FUZZ = dict(derandomize=True, database=None, deadline=None, print_blob=True,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
SEEDS = {fmt: seeds(fmt, SHARED if SHARED.is_dir() else None) for fmt in FORMATS}


@pytest.fixture(scope="module")
def sandbox():
    with Sandbox(memory_bytes=1 << 30, time_limit=30.0) as sb:
        yield sb


def _ok(outcome) -> None:
    assert outcome.ok, f"{outcome.kind}: {outcome.detail}"


def _chooser(data):
    return lambda n: data.draw(st.integers(0, n - 1))


@pytest.mark.parametrize("fmt", MOTION_FORMATS)
@settings(max_examples=MUTATED, **FUZZ)
@given(data=st.data())
def test_mutated_files(sandbox, fmt, data):
    choose = _chooser(data)
    base, skeleton = SEEDS[fmt][choose(len(SEEDS[fmt]))]
    _ok(sandbox.run(fmt, mutate(base, choose, fmt), skeleton))


@pytest.mark.parametrize("fmt", MOTION_FORMATS)
@settings(max_examples=CRAFTED, **FUZZ)
@given(data=st.data())
def test_crafted_files(sandbox, fmt, data):
    _ok(sandbox.run(fmt, *crafted(fmt, _chooser(data))))


@pytest.mark.parametrize("fmt", SIDECARS)
@settings(max_examples=SIDE_MUTATED, **FUZZ)
@given(data=st.data())
def test_mutated_sidecars(sandbox, fmt, data):
    choose = _chooser(data)
    base, _ = SEEDS[fmt][choose(len(SEEDS[fmt]))]
    _ok(sandbox.run(fmt, mutate(base, choose, fmt)))


@pytest.mark.parametrize("fmt", SIDECARS)
@settings(max_examples=SIDE_CRAFTED, **FUZZ)
@given(data=st.data())
def test_crafted_sidecars(sandbox, fmt, data):
    _ok(sandbox.run(fmt, *crafted(fmt, _chooser(data))))


# ------------------------------------------------------------------ the issue's findings
def _mat_double_tag_as_8() -> bytes:
    """A small MAT file whose first double array's data tag says type 8 instead of 9 (it
    made scipy's reader die with SIGSEGV)."""
    import scipy.io as sio
    buf = io.BytesIO()
    sio.savemat(buf, {"Motion": np.zeros((2, 3))})
    data = buf.getvalue()
    i = 128 + 8 + 16 + 16 + 16  # header, matrix tag, flags, dimensions, name: the data tag
    assert data[i:i + 4] == b"\x09\x00\x00\x00"
    return data[:i] + b"\x08" + data[i + 1:]


def _asf_child_first(n: int) -> bytes:
    bones = "".join(f"begin\nname b{i}\ndirection 0 1 0\nlength 1\ndof rx\nend\n"
                    for i in reversed(range(n)))
    hier = "".join(f"b{i - 1} b{i}\n" if i else "root b0\n" for i in reversed(range(n)))
    return f":units\nangle deg\n:bonedata\n{bones}:hierarchy\nbegin\n{hier}end\n".encode()


def _bvh_447_gib() -> bytes:
    """9,990 nested joints and 1,000,000 frames of one channel: 2 MB that once asked numpy
    for hundreds of GiB once a Motion was built."""
    head = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n" + "".join(
        f"JOINT j{i}\n{{\nOFFSET 0 1 0\nCHANNELS 0\n" for i in range(1, 9990))
    tail = "End Site\n{\nOFFSET 0 1 0\n}\n" + "}\n" * 9990
    return (head + tail + "MOTION\nFrames: 1000000\nFrame Time: 0.01\n").encode() + \
        b"0\n" * 1_000_000


def _mit_with(field: str, value) -> bytes:
    tree = mit_tree(2)
    tree[1][field] = value
    return write_mit(tree, [mit_sequence()])


def _h3d_with(name: str, data, body: str = "kit", **kw) -> bytes:
    """A tiny HumanML3D-layout folder (packed) with file ``name`` replaced by ``data``
    (bytes, or an array saved as ``.npy``)."""
    files = h3d_files(body, **kw)
    files[name] = data if isinstance(data, bytes) else npy_bytes(data)
    return pack_h3d(files, body)


def _npy_huge() -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "<f4", "fortran_order": False, "shape": (2 ** 40, 251)})
    return buf.getvalue() + bytes(16)


def _npy_unterminated() -> bytes:
    """A header numpy's parser dies on with tokenize.TokenError (an open bracket)."""
    good = npy_bytes(np.zeros((2, 251), np.float32))
    end = good.index(b"\n")
    head = good[:10] + b"{'descr': '<f4', 'fortran_order': False, 'shape': (2, 251"
    return head + b" " * (end - len(head)) + good[end:]


def _zip_member(fmt: str, member_suffix: str, body: bytes) -> bytes:
    """A seed of ``fmt`` (an npz-based file) with the member ending ``member_suffix``
    replaced by ``body`` (its CRC recomputed, so that the content checks are reached)."""
    import zipfile
    src = zipfile.ZipFile(io.BytesIO(sidecar_seeds(fmt)[0]))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as dst:
        for info in src.infolist():
            data = body if info.filename.endswith(member_suffix) else src.read(info)
            dst.writestr(info, data)
    return out.getvalue()


def _npy_shape(shape: tuple) -> bytes:
    """A .npy header declaring ``shape`` (beyond a C long: numpy's OverflowError)."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "<f4", "fortran_order": False, "shape": shape})
    return buf.getvalue() + bytes(16)


def _glb_zero_quaternion() -> bytes:
    import struct
    data = bytearray(sidecar_seeds("glb")[0])
    one = struct.pack("<f", 1.0)   # every w = 1 of a unit rotation becomes 0
    return bytes(data).replace(b"\x00" * 12 + one, b"\x00" * 16)


FINDINGS = [
    ("captions", lambda: b"file,text\na.bvh,walks\n", None, "VALID"),   # read(2 GiB) once
    ("npz", lambda: _zip_member("npz", "W.npy", b"not an npy member"), None, "not an array"),
    ("npz", lambda: _zip_member("npz", "W.npy", _npy_unterminated()), None, "a damaged"),
    ("index", lambda: _zip_member("index", "vectors.npy", b"raw"), None, "is not an array"),
    ("index", lambda: _zip_member("index", "spans.npy", _npy_unterminated()), None,
     "an array does not read"),
    ("glb", _glb_zero_quaternion, None, "no unit quaternion"),
    ("index", lambda: _zip_member("index", "vectors.npy", _npy_shape((2 ** 70, 8))), None,
     "declares 37,778,931,862,957,161,709,568 bytes of data"),
    ("npz", lambda: _zip_member("npz", "W.npy", _npy_shape((2 ** 70, 4))), None, "a damaged"),
    ("mit", _mat_double_tag_as_8, None, "number data of element type 8"),
    ("mit", lambda: _mit_with("parent", "text"), None, "parent must be numbers"),
    ("mit", lambda: _mit_with("or", "abc"), None, "or must be numbers"),
    ("mit", lambda: write_mit(mit_tree(2), "Motion"), None, "'Motion' must be a cell"),
    ("mit", lambda: write_mit([{k: v for k, v in n.items() if k != "offset"}
                               for n in mit_tree(2)], [mit_sequence()]), None, "no 'offset'"),
    ("asf", lambda: _asf_child_first(16000), None, "exceeds the limit"),
    ("amc", lambda: b"1\nroot 0 0 0 0 0 0\nchest 0 0 0\nlarm 0\nrarm 0\n" + b"9" * 5000 + b"\n",
     TINY_ASF, "out of range"),
    ("amc", lambda: "\u00b2\nroot 0 0 0 0 0 0\n".encode(), TINY_ASF, "expected a frame number"),
    ("mmm", lambda: b"<?xml version='1.0' encoding='utf-32'?><MMM/>", None, "encoding"),
    ("mmm", lambda: b"<?xml version='1.0' encoding='klingon'?><MMM/>", None, "encoding"),
    ("bvh", _bvh_447_gib, None, "exceeds the limit"),
    ("h3d", lambda: _h3d_with("new_joints/000001.npy", np.empty((2, 3), dtype=object)), None,
     "not real numbers"),
    ("h3d", lambda: _h3d_with("new_joints/000001.npy", _npy_huge()), None, "header declares"),
    ("h3d", lambda: _h3d_with("new_joints/000001.npy", _npy_unterminated()), None,
     "not a readable .npy file"),
    ("h3d", lambda: _h3d_with("new_joint_vecs/000001.npy", np.full((3, 251), np.nan, np.float32)),
     None, "non-finite"),
    ("h3d", lambda: _h3d_with("new_joints/000001.npy", np.zeros((3, 21, 3), np.float32)), None,
     "sits on its parent"),
    ("h3d", lambda: _h3d_with("texts/000001.txt", "walks#w#0#0\n".encode("utf-16")), None,
     "not UTF-8"),
    ("h3d", lambda: _h3d_with("texts/000001.txt", b"walks#w#2.0#1.0\n"), None,
     "ends before it starts"),
    ("h3d", lambda: _h3d_with("texts/000001.txt", b"walks#w#inf#inf\n"), None,
     "not two finite times"),
    ("h3d", lambda: _h3d_with("texts/000001.txt", b"walks#w#1e308#1e308\n"), None,
     "holds no frames"),
]


@pytest.mark.parametrize("fmt, make, skeleton, words", FINDINGS,
                         ids=[f"{f[0]}-{f[3][:20]}" for f in FINDINGS])
def test_findings_are_clean_errors(sandbox, fmt, make, skeleton, words):
    out = sandbox.run(fmt, make(), skeleton)
    if words == "VALID":
        assert out.kind == "valid", out
    else:
        assert out.kind == "error" and words in out.detail, out


def test_h3d_split_files_naming_missing_ids_and_paths(sandbox):
    # every motion listed (one left out is an error naming it), the rest odd names
    data = _h3d_with("train.txt", b"../x\n/etc/passwd\nmissing\n000001\nM000001\n"
                     + b"a" * 100_000)
    assert sandbox.run("h3d", data).kind == "valid"


def test_sandbox_reports_crashes_and_hangs(tmp_path):
    with Sandbox(time_limit=30.0) as sb:
        assert sb.run("bvh", SEEDS["bvh"][0][0]).kind == "valid"
        os.kill(sb.proc.pid, signal.SIGSEGV)  # our own child, as if a reader crashed it
        sb.proc.wait()
        out = sb.run("bvh", SEEDS["bvh"][0][0])
        assert out.kind == "crash" and "SIGSEGV" in out.detail
        assert sb.run("bvh", SEEDS["bvh"][0][0]).kind == "valid"  # started again
        sb.time_limit = 1e-4
        assert sb.run("asf", _asf_child_first(1500)).kind == "hang"
        assert sb.starts == 2

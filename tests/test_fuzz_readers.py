"""Fuzzing every reader with mutated real files: the only acceptable outcomes are a
``MotionlangError`` or a valid ``Motion`` (finite arrays, consistent shapes, finite joint
positions) — never another exception and never a hang.

The real files are cut to their first few frames so that one parse takes milliseconds;
hypothesis runs derandomized (reproducible in CI), 600 examples per reader (ASF, AMC, BVH,
MMM XML and the MIT ``.mat``).
"""
from __future__ import annotations

import atexit
import re
import shutil
import tempfile
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motionlang.errors import MotionlangError
from motionlang.formats.asf_amc import read_amc, read_asf
from motionlang.formats.bvh import read_bvh, write_bvh
from motionlang.kinematics import Motion
from tests.conftest import SHARED
from tests.test_asf_amc import TINY_ASF, tiny_amc
from tests.test_bvh import HAND

EXAMPLES = 600
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, database=None,
                deadline=timedelta(seconds=2), print_blob=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
SPECIAL = [b"1e308", b"-1e308", b"nan", b"NaN", b"inf", b"-inf", b"1e999", b"", b"0x10",
           b"1e-400", b"123456789012345678901234567890", b"1.5.5", b"-", b"{", b"}", b"9" * 400]
NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
TOKEN = re.compile(rb"[^\s<>=']+")


def _cut_amc(text: str, frames: int) -> str:
    """The header and the first ``frames`` frames of an AMC text."""
    out, seen = [], 0
    for line in text.splitlines():
        if line.strip().isdigit():
            seen += 1
            if seen > frames:
                break
        out.append(line)
    return "\n".join(out) + "\n"


def _cut_mmm(text: str, frames: int) -> str:
    """An MMM XML text with only its first ``frames`` MotionFrame elements."""
    lines = text.splitlines()
    ends = [i for i, ln in enumerate(lines) if ln.strip() == "</MotionFrame>"]
    tail = lines[next(i for i, ln in enumerate(lines) if ln.strip() == "</MotionFrames>"):]
    return "\n".join(lines[:ends[frames - 1] + 1] + tail) + "\n"


def _write(name: str, data: bytes) -> Path:
    path = WORK / name
    path.write_bytes(data)
    return path


def _bases() -> dict[str, list[bytes]]:
    asf, amc = SHARED / "cmu35/35.asf", SHARED / "cmu35/35_01.amc"
    real = asf.is_file() and amc.is_file()
    bases = {
        "asf": [TINY_ASF.encode()] + ([asf.read_bytes()] if real else []),
        "amc": [_cut_amc(amc.read_text(), 3).encode()] if real else [],
        "bvh": [HAND.encode()],
        "mmm": [],
        "mit": [],
    }
    if real:  # a BVH with CMU's 38 joints, written by motionlang from two AMC frames
        m = read_amc(_write("base.amc", bases["amc"][0]), read_asf(asf))[:2]
        write_bvh(m, WORK / "base.bvh")
        bases["bvh"].append((WORK / "base.bvh").read_bytes())
    mmm = SHARED / "kitml/00001_mmm.xml"
    if mmm.is_file():
        bases["mmm"].append(_cut_mmm(mmm.read_text(), 3).encode())
    mit = SHARED / "mit/motion.mat"
    if mit.is_file():
        bases["mit"].append(_cut_mit(mit))
    return bases


def _cut_mit(path: Path) -> bytes:
    """Taylor's MIT ``motion.mat`` with two sequences of 3 and 2 frames (uncompressed MAT
    bytes, so that flipped bytes land in headers, the tree and the numbers alike)."""
    import io

    import scipy.io as sio
    d = sio.loadmat(str(path))
    seqs = np.empty((1, 2), dtype=object)
    seqs[0, 0], seqs[0, 1] = d["Motion"][0, 0][:3], d["Motion"][0, 1][:2]
    buf = io.BytesIO()
    sio.savemat(buf, {"skel": d["skel"], "Motion": seqs})
    return buf.getvalue()


WORK = Path(tempfile.mkdtemp(prefix="motionlang-fuzz-"))  # one folder per test process
atexit.register(shutil.rmtree, WORK, ignore_errors=True)
BASES = _bases()
TINY_ASF_PATH = WORK / "tiny.asf"
TINY_ASF_PATH.write_text(TINY_ASF)
TINY_AMC = tiny_amc([([0, 1, 2, 3, 4, 5], [10, 20, 30], 40, 50)] * 3).encode()


@st.composite
def mutated(draw, bases: list[bytes]) -> bytes:
    """One of ``bases`` with 1-3 random edits: truncation, a flipped byte, a deleted,
    duplicated or swapped line, a number replaced by an extreme or broken one, a word
    replaced by another word of the file, inserted garbage."""
    data = draw(st.sampled_from(bases))
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["truncate", "flip", "delete", "duplicate", "swap",
                                   "number", "number", "token", "garbage"]))
        lines = data.split(b"\n")
        if op == "truncate":
            data = data[:draw(st.integers(0, len(data)))]
        elif op == "flip" and data:
            i = draw(st.integers(0, len(data) - 1))
            data = data[:i] + bytes([draw(st.integers(0, 255))]) + data[i + 1:]
        elif op in ("delete", "duplicate", "swap"):
            i = draw(st.integers(0, len(lines) - 1))
            if op == "delete":
                del lines[i]
            elif op == "duplicate":
                lines.insert(i, lines[i])
            else:
                j = draw(st.integers(0, len(lines) - 1))
                lines[i], lines[j] = lines[j], lines[i]
            data = b"\n".join(lines)
        elif op == "number":
            spans = [m.span() for m in NUMBER.finditer(data)]
            if spans:
                a, b = spans[draw(st.integers(0, len(spans) - 1))]
                data = data[:a] + draw(st.sampled_from(SPECIAL)) + data[b:]
        elif op == "token":  # a word replaced by another word of the file (a keyword...)
            spans = [m.span() for m in TOKEN.finditer(data)]
            if spans:
                a, b = spans[draw(st.integers(0, len(spans) - 1))]
                c, d = spans[draw(st.integers(0, len(spans) - 1))]
                data = data[:a] + data[c:d] + data[b:]
        elif op == "garbage":
            i = draw(st.integers(0, len(data)))
            data = data[:i] + draw(st.binary(max_size=24)) + data[i:]
    return data


def _check(read) -> None:
    """Run ``read()``; accept a MotionlangError or a valid Motion."""
    try:
        m = read()
    except MotionlangError:
        return
    if not isinstance(m, Motion):  # read_asf returns a Skeleton: check its numbers
        offsets = m.offsets
        assert np.all(np.isfinite(offsets)) and np.isfinite(m.file_unit) and m.file_unit > 0
        return
    T = m.n_frames
    assert T >= 1 and np.isfinite(m.fps) and m.fps > 0
    assert m.root_translation.shape == (T, 3)
    assert m.root_rotation.shape == (T, len(m.skeleton.root_axes))
    assert m.joint_angles.shape == (T, m.skeleton.ndof)
    for arr in (m.root_translation, m.root_rotation, m.joint_angles):
        assert np.all(np.isfinite(arr))
    assert np.all(np.isfinite(m.positions()))


@FUZZ
@given(mutated(BASES["asf"]))
def test_fuzz_asf(data):
    _check(lambda: read_asf(_write("fuzz.asf", data)))


@pytest.fixture(scope="module")
def cmu35():
    path = SHARED / "cmu35/35.asf"
    if not BASES["amc"] or not path.is_file():
        pytest.skip("real CMU subject 35 not present")
    return read_asf(path)


@FUZZ
@given(data=mutated(BASES["amc"] or [TINY_AMC]))
def test_fuzz_amc(cmu35, data):
    _check(lambda: read_amc(_write("fuzz.amc", data), cmu35))


@FUZZ
@given(mutated(BASES["bvh"]))
def test_fuzz_bvh(data):
    _check(lambda: read_bvh(_write("fuzz.bvh", data)))


@FUZZ
@given(data=mutated(BASES["mit"] or [b"MATLAB"]))
@pytest.mark.filterwarnings("ignore::UserWarning")  # scipy on corrupt headers
def test_fuzz_mit(data):
    from motionlang.formats.mit import read_mit
    if not BASES["mit"]:
        pytest.skip("real MIT motion.mat not present")
    try:
        motions = read_mit(_write("fuzz.mat", data))
    except MotionlangError:
        return
    assert motions
    for m in motions:
        _check(lambda: m)


@FUZZ
@given(data=mutated(BASES["mmm"] or [b"<MMM/>"]))
def test_fuzz_mmm(data):
    mmm = pytest.importorskip("motionlang.formats.mmm")
    if not BASES["mmm"]:
        pytest.skip("real KIT motion 00001 not present")
    _check(lambda: mmm.read_mmm(_write("fuzz_mmm.xml", data)))

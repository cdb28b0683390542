"""A model file whose bytes were damaged is refused before it is used (issue 44, item 0):
``torch.load`` does not check the zip members' CRCs, ``check_archive`` does."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest
import torch

from motionlang.errors import MotionlangError
from motionlang.models.checkpoint import load_checkpoint, write_checkpoint
from motionlang.models.versions import check_archive


def _flip_weight_byte(path) -> str:
    """Flip one byte inside the stored tensor data; returns the member's name."""
    with zipfile.ZipFile(path) as zf:
        info = next(i for i in zf.infolist() if "/data/" in i.filename and i.file_size >= 64)
    raw = bytearray(path.read_bytes())
    # the local header: 30 bytes + name + extra, then the (stored) member's bytes
    name_len = int.from_bytes(raw[info.header_offset + 26:info.header_offset + 28], "little")
    extra_len = int.from_bytes(raw[info.header_offset + 28:info.header_offset + 30], "little")
    at = info.header_offset + 30 + name_len + extra_len + 5
    raw[at] ^= 0xFF
    path.write_bytes(bytes(raw))
    return info.filename


def test_a_flipped_weight_byte_is_refused_naming_the_member(tmp_path):
    path = tmp_path / "model.pt"
    write_checkpoint({"kind": "x", "w": torch.arange(64, dtype=torch.float32)}, path)
    assert float(load_checkpoint(path)["w"].sum()) == float(sum(range(64)))
    member = _flip_weight_byte(path)
    # without the check torch reads the changed number silently
    assert float(torch.load(path, weights_only=True)["w"].sum()) != float(sum(range(64)))
    with pytest.raises(MotionlangError, match="damaged checkpoint") as err:
        load_checkpoint(path)
    assert str(path) in str(err.value) and member in str(err.value)
    assert "\n" not in str(err.value)


def test_an_intact_archive_and_a_non_zip_pass(tmp_path):
    npz = tmp_path / "a.npz"
    np.savez(npz, a=np.arange(10))
    check_archive(npz)
    other = tmp_path / "legacy.bin"
    other.write_bytes(b"not a zip at all")
    check_archive(other)   # left to its loader
    with pytest.raises(MotionlangError, match="not a readable"):
        load_checkpoint(other)

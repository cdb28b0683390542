"""Reader limits: defaults, environment overrides, one-line messages naming the variable."""
from __future__ import annotations

import pytest

from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.utils import limits


def test_defaults_and_overrides(monkeypatch):
    assert limits.current() == limits.Limits()
    monkeypatch.setenv("MOTIONLANG_MAX_FRAMES", "5000000")
    monkeypatch.setenv("MOTIONLANG_MAX_MEMORY", "16G")
    monkeypatch.setenv("MOTIONLANG_MAX_FILE_BYTES", "500MiB")
    monkeypatch.setenv("MOTIONLANG_MAX_ARCHIVE_RATIO", "250.5")
    lim = limits.current()
    assert (lim.max_frames, lim.max_memory_bytes, lim.max_file_bytes, lim.max_archive_ratio) \
        == (5_000_000, 16 << 30, 500 << 20, 250.5)
    assert lim.max_joints == limits.Limits().max_joints


@pytest.mark.parametrize("value", ["lots", "-5", "0", "8X", "1e30"])
def test_bad_values_are_one_line_errors(monkeypatch, value):
    monkeypatch.setenv("MOTIONLANG_MAX_JOINTS", value)
    with pytest.raises(MotionlangError, match="MOTIONLANG_MAX_JOINTS="):
        limits.current()


def test_messages_name_the_file_and_the_variable(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLANG_MAX_JOINTS", "10")
    with pytest.raises(MotionFormatError) as info:
        limits.check(tmp_path / "x.bvh", "max_joints", 11, "joint count", line=7)
    assert str(info.value) == (f"{tmp_path / 'x.bvh'}:7: joint count 11 exceeds the limit of "
                               "10 (raise it with MOTIONLANG_MAX_JOINTS=...)")
    limits.check_motion(None, 100, 10, 30)  # within every limit
    with pytest.raises(MotionFormatError, match="memory needed for 10,000,000 frames of 10 "
                                                "joints 11.2 GiB exceeds the limit of 4 GiB"):
        limits.check_motion(None, 10_000_000, 10)
    (tmp_path / "big.amc").write_bytes(b"0" * 2048)
    monkeypatch.setenv("MOTIONLANG_MAX_MEMORY", "8K")
    assert limits.check_file(tmp_path / "big.amc", 4) == 2048
    with pytest.raises(MotionFormatError, match="memory needed to parse it"):
        limits.check_file(tmp_path / "big.amc", 8)

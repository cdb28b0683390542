"""Atomic writes: recognisable temporary files, and the leftovers of a killed writer removed
by the next write into the folder (a SIGKILL cannot be caught; see utils/atomic.py)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from motionlang.utils import atomic
from motionlang.utils.atomic import TAG, atomic_path, atomic_write, sweep_stale

SRC = Path(__file__).resolve().parents[1] / "src"


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if TAG in p.name)


def test_temporary_names_are_recognisable(tmp_path):
    target = tmp_path / "model.pt"
    with atomic_path(target) as tmp:
        assert tmp.name.startswith(f".model.pt{TAG}") and tmp.suffix == ".pt"
        assert f".{os.getpid()}." in tmp.name
        tmp.write_bytes(b"x")
    assert target.read_bytes() == b"x" and _leftovers(tmp_path) == []
    with pytest.raises(RuntimeError), atomic_write(target) as fh:
        fh.write("half")
        raise RuntimeError("failed while writing")
    assert target.read_bytes() == b"x" and _leftovers(tmp_path) == []


@pytest.mark.skipif(os.name == "nt", reason="SIGKILL")
def test_a_killed_writers_leftover_is_removed_by_the_next_write(tmp_path):
    target = tmp_path / "checkpoint.pt"
    code = ("import os, signal, sys\nfrom motionlang.utils.atomic import atomic_write\n"
            "with atomic_write(sys.argv[1], 'wb') as fh:\n"
            "    fh.write(b'partial'); fh.flush(); os.kill(os.getpid(), signal.SIGKILL)\n")
    env = dict(os.environ, PYTHONPATH=str(SRC))
    proc = subprocess.run([sys.executable, "-c", code, str(target)], env=env)
    assert proc.returncode == -signal.SIGKILL
    assert len(_leftovers(tmp_path)) == 1 and not target.exists()
    with atomic_write(target, "wb") as fh:
        fh.write(b"complete")
    assert target.read_bytes() == b"complete" and _leftovers(tmp_path) == []


def test_live_and_foreign_temporaries_are_kept(tmp_path, monkeypatch):
    mine = atomic.make_temp(tmp_path / "a.png", ".png")           # this process: alive
    other_host = tmp_path / f".a.png{TAG}elsewhere-1.{os.getpid()}.abcd1234.png"
    other_host.write_bytes(b"")
    old = tmp_path / f".b.png{TAG}elsewhere-1.77.abcd1234.png"
    old.write_bytes(b"")
    os.utime(old, (time.time() - 2 * atomic.FOREIGN_STALE_S,) * 2)
    unrelated = tmp_path / ".a.png.tmp"
    unrelated.write_bytes(b"")
    removed = sweep_stale(tmp_path, force=True)
    assert removed == [old]
    assert mine.exists() and other_host.exists() and unrelated.exists()

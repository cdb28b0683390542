"""Checked writes (issue 44, item 1): a failed write is one error naming the path and the
cause, the old target untouched, no temporary file; SIGTERM cleans up like Ctrl-C; the
optional cache never stops a run; split files are all written or none."""
from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from helpers.patching import patch_everywhere
from motionlang.cli.main import main
from motionlang.datasets import cache
from motionlang.datasets.splits import save_splits
from motionlang.errors import MotionlangError
from motionlang.utils.atomic import TAG, WriteError, atomic_path, atomic_write, new_folder

SRC = Path(__file__).resolve().parents[1] / "src"


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if TAG in p.name)


def _full(*_args, **_kw):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_a_full_disk_is_one_error_naming_the_path_and_the_cause(tmp_path):
    target = tmp_path / "model.npz"
    target.write_bytes(b"old")
    with pytest.raises(WriteError) as err, atomic_path(target) as tmp:
        tmp.write_bytes(b"half")
        _full()
    assert str(err.value) == f"{target}: cannot write: disk full (No space left on device)"
    assert target.read_bytes() == b"old" and _leftovers(tmp_path) == []


def test_an_error_hidden_in_a_writers_chain_is_found(tmp_path):
    # torch and imageio report the file system's error as one of their own
    target = tmp_path / "a.mp4"
    with pytest.raises(WriteError, match="(?i)read-only file system"), atomic_path(target):
        try:
            raise OSError(errno.EROFS, "Read-only file system")
        except OSError as exc:
            raise RuntimeError("writer failed") from exc
    # a plain bug stays what it is
    with pytest.raises(RuntimeError, match="a bug"), atomic_path(target):
        raise RuntimeError("a bug")
    assert not target.exists() and _leftovers(tmp_path) == []


def test_a_writer_that_leaves_an_empty_file_is_refused(tmp_path):
    target = tmp_path / "anim.gif"
    target.write_bytes(b"GIF89a old")
    with pytest.raises(WriteError, match="the writer produced 0 bytes"), atomic_path(target):
        pass
    assert target.read_bytes() == b"GIF89a old" and _leftovers(tmp_path) == []
    with atomic_write(tmp_path / "empty.txt") as fh:   # text may be empty
        fh.write("")
    assert (tmp_path / "empty.txt").read_text() == ""


def test_a_folder_that_is_a_file_is_named_as_such(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(WriteError, match="afile/x.txt: cannot write: a file stands where a "
                                         "folder is needed"):
        with atomic_write(tmp_path / "afile" / "x.txt") as fh:
            fh.write("y")


def test_the_cli_turns_any_os_error_into_one_line(tmp_path, capsys, monkeypatch):
    from motionlang.formats import mmm
    patch_everywhere(monkeypatch, mmm, "write_mmm", _full)   # a raw OSError, outside a checked write
    code = main(["data", "synth", "--out", str(tmp_path / "syn"), "--n", "2",
                 "--workers", "1"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "disk full" in err[0]
    assert not (tmp_path / "syn").exists()   # a failed first write leaves no folder


def test_new_folder_keeps_what_existed_and_removes_what_it_made(tmp_path):
    with pytest.raises(KeyboardInterrupt), new_folder(tmp_path / "a" / "b"):
        raise KeyboardInterrupt
    assert not (tmp_path / "a").exists()
    (tmp_path / "run").mkdir()
    with pytest.raises(MotionlangError), new_folder(tmp_path / "run"):
        raise MotionlangError("x")
    assert (tmp_path / "run").is_dir()
    with pytest.raises(MotionlangError), new_folder(tmp_path / "ckpt") as d:
        (d / "last.pt").write_bytes(b"resumable")
        raise MotionlangError("disk full later on")
    assert (tmp_path / "ckpt" / "last.pt").exists()   # files of a new folder stay


def test_split_files_are_all_written_or_none(tmp_path, monkeypatch):
    out = tmp_path / "splits"
    calls = []

    def write_text(self, text, encoding=None):
        calls.append(self.name)
        if len(calls) == 3:
            _full()
        with open(self, "w", encoding=encoding) as fh:
            fh.write(text)

    monkeypatch.setattr(Path, "write_text", write_text)
    with pytest.raises(WriteError, match="test.txt: cannot write: disk full"):
        save_splits({"train": ["1", "2"], "val": ["3"], "test": ["4"]}, out)
    assert len(calls) == 3 and not out.exists()
    monkeypatch.undo()
    paths = save_splits({"train": ["1", "2"], "val": [], "test": ["4"]}, out)
    assert [p.read_text() for p in paths] == ["1\n2\n", "", "4\n"]


@pytest.mark.parametrize("where", ["file", "readonly"])
def test_an_unusable_cache_warns_once_and_the_work_goes_on(tmp_path, monkeypatch, caplog, where):
    folder = tmp_path / "cache"
    if where == "file":
        folder.write_text("a file, not a folder")
    else:
        monkeypatch.setattr(cache, "atomic_write", lambda *a, **k: _raise_erofs())
    monkeypatch.setattr(cache, "_warned", set())
    for i in range(2):
        out = cache.cached({"i": i}, lambda: {"x": np.arange(3)}, directory=folder)
        assert out["x"].tolist() == [0, 1, 2]
    warnings = [r for r in caplog.records if "not used" in r.getMessage()]
    assert len(warnings) == 1 and str(folder) in warnings[0].getMessage()


def _raise_erofs():
    raise WriteError("cache/x.npz", OSError(errno.EROFS, "Read-only file system"))


@pytest.mark.skipif(os.name == "nt", reason="SIGTERM")
def test_sigterm_during_a_write_removes_the_temporary_file(tmp_path):
    target = tmp_path / "render.gif"
    target.write_bytes(b"previous")
    code = ("import sys, time\nfrom motionlang.utils.atomic import atomic_path\n"
            "from motionlang.utils.signals import sigterm_unwinds, stopped\n"
            "try:\n"
            "    with sigterm_unwinds(), atomic_path(sys.argv[1]) as tmp:\n"
            "        tmp.write_bytes(b'half'); print('ready', flush=True); time.sleep(30)\n"
            "except KeyboardInterrupt as exc:\n"
            "    sys.exit(stopped(exc))\n")
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    # SIGTERM at its default in the child, whatever the test runner's process inherited
    # (an ignored SIGTERM is inherited, and sigterm_unwinds leaves a set disposition alone)
    p = subprocess.Popen([sys.executable, "-c", code, str(target)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env,
                         preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))
    assert p.stdout.readline().strip() == "ready"
    assert len(_leftovers(tmp_path)) == 1
    t0 = time.monotonic()
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 128 + signal.SIGTERM and err.strip() == "terminated"
    assert time.monotonic() - t0 < 10
    assert target.read_bytes() == b"previous" and _leftovers(tmp_path) == []


@pytest.mark.parametrize("dest", ["", "afile", "/proc/motionlang-x"])
def test_download_dest_that_cannot_be_a_folder_is_one_line(tmp_path, capsys, monkeypatch, dest):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("a file")
    assert main(["data", "download", "kitml", "--dest", dest]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "argument --dest" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_a_resume_whose_checkpoint_does_not_read_writes_nothing(tmp_path, capsys):
    from motionlang.datasets.synth.corpus import write_corpus
    write_corpus(tmp_path / "c", 3, workers=1, show_progress=False)
    run = tmp_path / "old"
    run.mkdir()
    (run / "last.pt").write_bytes(b"PK\x03\x04" + b"\0" * 60)   # a run from before run.json
    assert main(["train", "m2l", "--data", str(tmp_path / "c"), "--out", str(run),
                 "--resume"]) == 2
    assert "last.pt" in capsys.readouterr().err
    assert sorted(p.name for p in run.iterdir()) == ["last.pt"]


def test_an_interrupt_a_library_turns_into_its_own_error_still_stops_the_command(
        capsys, monkeypatch):
    # matplotlib's C code can turn the KeyboardInterrupt of a Ctrl-C into a ValueError
    # ("Invalid affine transformation matrix"): the command must still end as interrupted
    import motionlang.cli.motion_commands as mc

    def masked(args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)
        except KeyboardInterrupt:
            raise ValueError("Invalid affine transformation matrix") from None
        return 0

    monkeypatch.setattr(mc, "cmd_info", masked)
    # a test run in a background job (or an xdist worker) may inherit SIGINT ignored
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        assert main(["info", "x.bvh"]) == 130
    finally:
        signal.signal(signal.SIGINT, before)
    assert capsys.readouterr().err.strip() == "interrupted"

    def broken(args):
        raise ValueError("a real bug")

    monkeypatch.setattr(mc, "cmd_info", broken)
    with pytest.raises(ValueError, match="a real bug"):   # no signal: not hidden
        main(["info", "x.bvh"])

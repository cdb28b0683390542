"""A run folder is never clobbered (issue 44, item 0): a finished or busy run refuses a
second ``train``; ``--resume`` refuses changed data, seed or data options before writing
anything; ``--overwrite`` replaces the run; the lock of a dead process is taken over."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from motionlang.cli.main import main
from motionlang.errors import MotionlangError
from motionlang.training.run_guard import check_identity, keep_splits, run_identity
from motionlang.utils.folder_lock import LOCK_NAME, folder_lock

torch.set_num_threads(1)
TINY = ["--epochs", "1", "--batch-size", "8", "--offsets", "1", "--enc-hidden", "8",
        "--dec-hidden", "8", "--embed-dim", "8", "--dec-layers", "1"]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    from motionlang.datasets.synth.corpus import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, 6, seed=3, workers=1, show_progress=False)
    return root


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))


def train(corpus: Path, out: Path, *extra: str) -> int:
    return main(["train", "m2l", "--data", str(corpus), "--out", str(out), *TINY, *extra])


@pytest.fixture(scope="module")
def finished(corpus, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("runs") / "m2l"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MOTIONLANG_CACHE", str(out.parent / "cache"))
        assert train(corpus, out) == 0
    return out


@pytest.fixture
def run(finished, tmp_path) -> Path:
    """A copy of the finished run to try things on."""
    return Path(shutil.copytree(finished, tmp_path / "run"))


def digests(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def one_line(capsys, *needles: str) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    for n in needles:
        assert n in err, err
    return err


def test_a_finished_run_refuses_a_second_train(corpus, run, capsys):
    before = digests(run)
    assert {"model.pt", "last.pt", "run.json", "splits/test.txt"} <= set(before)
    assert train(corpus, run) == 2
    one_line(capsys, "not empty", "--resume", "--overwrite")
    assert digests(run) == before


def test_overwrite_replaces_the_run_and_keeps_other_files(corpus, run, capsys):
    (run / "notes.txt").write_text("mine")
    (run / "stale_from_old_run.txt").write_text("x")
    old_model = (run / "model.pt").read_bytes()
    assert train(corpus, run, "--overwrite", "--seed", "5") == 0
    assert (run / "notes.txt").read_text() == "mine"
    assert json.loads((run / "run.json").read_text())["seed"] == 5
    assert (run / "model.pt").read_bytes() != old_model
    assert len((run / "commands.jsonl").read_text().splitlines()) == 1   # a new log


@pytest.mark.parametrize("change", [["--seed", "7"], ["--min-count", "2"],
                                    ["--max-seconds", "20"]])
def test_a_resume_with_other_data_options_writes_nothing(corpus, run, capsys, change):
    before = digests(run)
    assert train(corpus, run, "--resume", "--epochs", "2", *change) == 2
    one_line(capsys, "--resume", change[0], "started with other")
    assert digests(run) == before


def test_a_resume_with_the_runs_options_continues(corpus, run, capsys):
    splits = (run / "splits" / "test.txt").read_bytes()
    assert train(corpus, run, "--resume", "--epochs", "2") == 0
    assert json.loads((run / "history.json").read_text())[-1]["epoch"] == 2
    assert (run / "splits" / "test.txt").read_bytes() == splits
    assert not (run / LOCK_NAME).exists()   # released


def test_a_busy_run_folder_refuses_a_second_process(corpus, tmp_path, capsys):
    out = tmp_path / "busy"
    out.mkdir()
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        from motionlang.utils.atomic import _host
        (out / LOCK_NAME).write_text(json.dumps({"pid": sleeper.pid, "host": _host()}))
        assert train(corpus, out) == 2
        one_line(capsys, f"in use by process {sleeper.pid}")
        assert os.listdir(out) == [LOCK_NAME]       # nothing written, the lock kept
    finally:
        sleeper.kill()
        sleeper.wait()
    # its process gone, the lock is stale: taken over, and released at the end
    assert train(corpus, out) == 0
    assert (out / "model.pt").is_file() and not (out / LOCK_NAME).exists()


def test_a_run_in_progress_is_named_busy_not_just_non_empty(corpus, run, capsys):
    from motionlang.utils.atomic import _host
    (run / LOCK_NAME).write_text(json.dumps({"pid": os.getppid(), "host": _host()}))
    before = digests(run)
    for extra in ([], ["--resume", "--epochs", "2"], ["--overwrite"]):
        assert train(corpus, run, *extra) == 2
        one_line(capsys, f"in use by process {os.getppid()}")
    assert digests(run) == before


def test_sigterm_releases_the_lock(corpus, tmp_path):
    import signal
    import time
    out = tmp_path / "term"
    env = {**os.environ, "MOTIONLANG_CACHE": str(tmp_path / "cache"), "OMP_NUM_THREADS": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "motionlang.cli.main", "train", "m2l",
                             "--data", str(corpus), "--out", str(out), *TINY, "--epochs",
                             "1000"], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not (out / LOCK_NAME).exists() and proc.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.05)
        assert (out / LOCK_NAME).exists(), proc.stderr.read() if proc.poll() is not None else ""
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=120) == 128 + signal.SIGTERM
    finally:
        proc.kill()
        proc.wait()
    assert not (out / LOCK_NAME).exists()


def test_another_hosts_lock_is_never_guessed_stale(tmp_path):
    (tmp_path / LOCK_NAME).write_text(json.dumps({"pid": 1, "host": "elsewhere"}))
    with pytest.raises(MotionlangError, match="process 1 on elsewhere"), folder_lock(tmp_path):
        pass
    assert socket.gethostname() != "elsewhere"


def test_the_lock_is_released_on_an_error_and_a_made_folder_removed(tmp_path):
    out = tmp_path / "a" / "b"
    with pytest.raises(KeyboardInterrupt), folder_lock(out):
        assert (out / LOCK_NAME).is_file()
        raise KeyboardInterrupt   # what SIGTERM becomes under utils.signals
    assert not (tmp_path / "a").exists()


def test_a_failed_first_run_leaves_no_folder(tmp_path, capsys):
    out = tmp_path / "new" / "run"
    assert train(tmp_path / "no_such_data", out) == 2
    assert not (tmp_path / "new").exists()


def test_identity_lists_every_change(tmp_path):
    (tmp_path / "run.json").write_text(json.dumps(
        run_identity("m2l", ["a"], 0, {"min_count": 1, "mirror": False})))
    check_identity(tmp_path, run_identity("m2l", ["a"], 0, {"min_count": 1, "mirror": True}),
                   may_change=("mirror",))
    with pytest.raises(MotionlangError, match=r"--data a -> b; --seed 0 -> 1; --min-count 1 -> 3"):
        check_identity(tmp_path, run_identity("m2l", ["b"], 1, {"min_count": 3,
                                                                "mirror": False}))


def test_a_resume_keeps_splits_and_refuses_changed_ones(tmp_path):
    folder = tmp_path / "splits"
    keep_splits({"train": ["a", "b"], "test": ["c"]}, folder, resume=False)
    before = digests(folder)
    keep_splits({"train": ["b", "a"], "test": ["c"]}, folder, resume=True)   # same sets
    with pytest.raises(MotionlangError, match=r"test split .* lacks c; adds d"):
        keep_splits({"train": ["a", "b"], "test": ["d"]}, folder, resume=True)
    assert digests(folder) == before


def test_a_resume_with_another_vocabulary_of_the_same_size_is_refused(tmp_path):
    from motionlang.training.run_files import check_same_data
    words = {"type": "Vocabulary", "data": {"itos": ["<pad>", "walk", "run"]}}
    other = {"type": "Vocabulary", "data": {"itos": ["<pad>", "run", "walk"]}}
    check_same_data(tmp_path, {"vocab": words}, {"vocab": words})
    with pytest.raises(MotionlangError, match="another vocab .3 -> 3 words, 2 ids"):
        check_same_data(tmp_path, {"vocab": words}, {"vocab": other})


def test_a_run_stopped_before_its_first_checkpoint_gets_one_advice(corpus, run, capsys):
    # as a run SIGTERM'd during its first epoch leaves it: run.json and splits, no last.pt
    for name in ("last.pt", "best.pt", "model.pt", "history.json", "loss_curve.png"):
        (run / name).unlink(missing_ok=True)
    assert train(corpus, run) == 2
    one_line(capsys, "stopped before its first checkpoint", "--overwrite")
    assert train(corpus, run, "--resume") == 2
    one_line(capsys, "no checkpoint", "--overwrite starts it again")
    assert train(corpus, run, "--overwrite") == 0
    assert (run / "last.pt").is_file()


def test_a_lock_on_a_full_disk_names_the_lock(tmp_path, monkeypatch):
    import errno

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(MotionlangError, match=f"cannot take the lock {tmp_path / LOCK_NAME}: "
                                              r"disk full \(No space left on device\)"):
        with folder_lock(tmp_path):
            pass
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == []   # no temporary file left


def test_a_stopped_train_says_how_its_run_goes_on(run, tmp_path):
    import argparse

    from motionlang.cli.main import _what_now
    args = argparse.Namespace(command="train", out=str(run))
    assert _what_now(args) == f"the same command with --resume continues the run in {run}"
    (run / "last.pt").unlink()
    for p in run.glob("*/last.pt"):
        p.unlink()
    assert "holds no checkpoint yet (--overwrite" in _what_now(args)
    assert _what_now(argparse.Namespace(command="describe", out=str(run))) == ""
    assert _what_now(argparse.Namespace(command="train", out=str(tmp_path / "none"))) == ""

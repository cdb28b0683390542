"""Resumable download, checksum, offline and HTTP errors, safe extraction (local server)."""
from __future__ import annotations

import hashlib
import io
import zipfile

import pytest

from helpers.http_server import free_port, serve
from motionlang.datasets.download import download_file, safe_extract, safe_extract_tar
from motionlang.errors import DatasetError
from motionlang.utils import atomic
from motionlang.utils.atomic import TAG

PAYLOAD = bytes(range(256)) * 4000  # ~1 MB, spans several read chunks


def test_full_download_with_checksum(tmp_path):
    digest = hashlib.sha256(PAYLOAD).hexdigest()
    with serve(PAYLOAD) as srv:
        out = download_file(srv.url, tmp_path / "a.zip", sha256=digest)
        assert out.read_bytes() == PAYLOAD
        assert not (tmp_path / "a.zip.part").exists()
        download_file(srv.url, tmp_path / "a.zip", sha256=digest)   # present: no request
        assert len(srv.requests) == 1


def test_interrupted_download_resumes_with_range(tmp_path):
    target = tmp_path / "a.zip"
    with serve(PAYLOAD, mode="cut") as srv:
        with pytest.raises(DatasetError, match=srv.url):
            download_file(srv.url, target)
        part = tmp_path / "a.zip.part"
        assert not target.exists() and part.stat().st_size == len(PAYLOAD) // 2
        srv.mode = "ok"
        download_file(srv.url, target, sha256=hashlib.sha256(PAYLOAD).hexdigest())
        assert srv.requests[-1][1] == f"bytes={len(PAYLOAD) // 2}-"
    assert target.read_bytes() == PAYLOAD and not part.exists()


def test_server_ignoring_range_restarts(tmp_path):
    (tmp_path / "a.bin.part").write_bytes(b"x" * 1000)   # stale bytes that are no prefix
    with serve(PAYLOAD, mode="norange") as srv:
        download_file(srv.url, tmp_path / "a.bin")   # not named as an archive: not checked
        assert srv.requests[0][1] == "bytes=1000-"
    assert (tmp_path / "a.bin").read_bytes() == PAYLOAD


def test_checksum_mismatch(tmp_path):
    with serve(PAYLOAD) as srv:
        with pytest.raises(DatasetError, match="sha256 mismatch") as ei:
            download_file(srv.url, tmp_path / "a.zip", sha256="0" * 64)
        assert srv.url in str(ei.value)
    assert not (tmp_path / "a.zip").exists() and not (tmp_path / "a.zip.part").exists()


def test_offline_and_http_errors(tmp_path):
    url = f"http://127.0.0.1:{free_port()}/data.zip"
    with pytest.raises(DatasetError, match="offline") as ei:
        download_file(url, tmp_path / "a.zip", timeout=5)
    assert url in str(ei.value)
    with serve(PAYLOAD) as srv:
        missing = srv.url.replace("data.zip", "nope.zip")
        with pytest.raises(DatasetError, match="404"):
            download_file(missing, tmp_path / "b.zip")
    with pytest.raises(DatasetError, match="http"):
        download_file("file:///etc/passwd", tmp_path / "c")


def _zip(path, members: dict[str, bytes]):
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return path


def test_safe_extract(tmp_path):
    good = _zip(tmp_path / "g.zip", {"top/a.txt": b"a", "top/sub/b.c3d": b"b"})
    out = safe_extract(good, tmp_path / "out", keep=lambda n: not n.endswith(".c3d"))
    assert (out / "top" / "a.txt").read_bytes() == b"a"
    assert not (out / "top" / "sub" / "b.c3d").exists()
    with pytest.raises(DatasetError, match="already exists"):
        safe_extract(good, out)
    for bad_name in ("../evil.txt", "/abs.txt", "a/../../evil.txt"):
        bad = _zip(tmp_path / "b.zip", {"ok.txt": b"1", bad_name: b"x"})
        with pytest.raises(DatasetError, match="unsafe path"):
            safe_extract(bad, tmp_path / "bad_out")
        assert not (tmp_path / "bad_out").exists()
        assert not (tmp_path / "evil.txt").exists()
    (tmp_path / "junk.zip").write_bytes(b"not a zip")
    with pytest.raises(DatasetError, match="not a valid zip"):
        safe_extract(tmp_path / "junk.zip", tmp_path / "j_out")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


# ------------------------------------------------------------------ hostile archives
HTML = b"<!DOCTYPE html>\n<html><body>Service temporarily unavailable</body></html>\n"


def _zip_bytes(members: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buf.getvalue()


def test_a_web_page_is_not_kept_as_the_archive(tmp_path):
    good = _zip_bytes({"a.txt": b"a"})
    with serve(HTML) as srv:
        with pytest.raises(DatasetError, match=r"web page \(HTML\), not the zip archive; "
                                               "nothing was kept"):
            download_file(srv.url, tmp_path / "a.zip")
        assert list(tmp_path.iterdir()) == []
        srv.payload = good                                   # the server is fixed
        assert download_file(srv.url, tmp_path / "a.zip").read_bytes() == good
        (tmp_path / "a.zip").write_bytes(HTML)               # as an older version saved it
        assert download_file(srv.url, tmp_path / "a.zip").read_bytes() == good
        assert len(srv.requests) == 3


def test_zip_bomb_is_refused_before_writing(tmp_path, monkeypatch):
    bomb = tmp_path / "bomb.zip"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf, zf.open("zeros.bin", "w") as fh:
        for _ in range(100):
            fh.write(bytes(1 << 20))                         # 100 MiB in ~100 KB
    with pytest.raises(DatasetError, match=r"refused: the sizes its members declare would "
                                           r"expand it to more than 64 MiB \(100 times the "
                                           r"archive's size, 64 MiB at least\); raise it with "
                                           "MOTIONLANG_MAX_ARCHIVE_RATIO"):
        safe_extract(bomb, tmp_path / "out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bomb.zip"]
    monkeypatch.setenv("MOTIONLANG_MAX_ARCHIVE_RATIO", "2000")
    monkeypatch.setenv("MOTIONLANG_MAX_ARCHIVE_BYTES", "50M")
    with pytest.raises(DatasetError, match="MOTIONLANG_MAX_ARCHIVE_BYTES"):
        safe_extract(bomb, tmp_path / "out")
    monkeypatch.setenv("MOTIONLANG_MAX_ARCHIVE_BYTES", "200M")
    assert (safe_extract(bomb, tmp_path / "out") / "zeros.bin").stat().st_size == 100 << 20


def test_zip_bomb_served_as_kitml(tmp_path):
    from motionlang.datasets.kitml import download_kitml
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf, zf.open("00001_mmm.xml", "w") as fh:
        for _ in range(100):
            fh.write(b" " * (1 << 20))
    with serve(buf.getvalue()) as srv, pytest.raises(DatasetError, match="refused"):
        download_kitml(tmp_path, url=srv.url)
    assert not (tmp_path / "kitml").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["data.zip"]


def _patch_zip(data: bytes, local: int, central: int, value: int) -> bytes:
    """Set a 2-byte field of every local header and central directory record."""
    out = bytearray(data)
    for sig, off in ((b"PK\x03\x04", local), (b"PK\x01\x02", central)):
        i = out.find(sig)
        while i >= 0:
            out[i + off:i + off + 2] = value.to_bytes(2, "little")
            i = out.find(sig, i + 4)
    return bytes(out)


@pytest.mark.parametrize("data, words", [
    (_zip_bytes({"d/a.txt": b"1", "d/b.txt": b"2"}).replace(b"d/b.txt", b"d/a.txt"),
     "name clash in archive: 'd/a.txt'"),
    (_zip_bytes({"d": b"1", "d/b.txt": b"2"}), "name clash in archive: 'd/b.txt'"),
    (_patch_zip(_zip_bytes({"a.txt": b"1"}), 6, 8, 0x1), "encrypted member 'a.txt'"),
    (_patch_zip(_zip_bytes({"a.txt": b"1"}), 8, 10, 99), "compression method 99"),
    (_zip_bytes({"a.txt": b"1"})[:-30], "not a valid zip archive"),
], ids=["name-clash", "file-and-folder", "encrypted", "compression", "truncated"])
# (named ids: the archives hold the time they were built, and pytest-xdist workers must
# collect the same test names)
def test_bad_zip_members_are_one_line_errors(tmp_path, data, words):
    (tmp_path / "x.zip").write_bytes(data)
    with pytest.raises(DatasetError, match=words) as info:
        safe_extract(tmp_path / "x.zip", tmp_path / "out")
    assert "\n" not in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.zip"]


def test_tar_name_clash_and_stale_extraction_folder(tmp_path):
    import tarfile
    with tarfile.open(tmp_path / "x.tar", "w") as tf:
        for name in ("d/a.txt", "d/a.txt"):
            info = tarfile.TarInfo(name)
            info.size = 1
            tf.addfile(info, io.BytesIO(b"1"))
    stale = tmp_path / f".out{TAG}{atomic._host()}.{_dead_pid()}.abcdefgh.extract"
    (stale / "half").mkdir(parents=True)
    with pytest.raises(DatasetError, match="name clash in archive: 'd/a.txt'"):
        safe_extract_tar(tmp_path / "x.tar", tmp_path / "out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.tar"]  # the stale one swept too


def _dead_pid() -> int:
    import subprocess
    import sys
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True)
    return int(proc.stdout)


def test_a_part_file_that_is_a_link_is_never_written_through(tmp_path):
    """A planted ``.part`` link (to a file the user owns) is refused and left alone; the
    file it points to keeps every byte (issue 44, item 0)."""
    victim = tmp_path / "precious.txt"
    victim.write_bytes(b"keep me")
    (tmp_path / "a.zip.part").symlink_to(victim)
    with serve(PAYLOAD) as srv:
        with pytest.raises(DatasetError, match="a symbolic link, not a partial download"):
            download_file(srv.url, tmp_path / "a.zip")
        assert srv.requests == []                       # refused before any request
    assert victim.read_bytes() == b"keep me"
    assert (tmp_path / "a.zip.part").is_symlink() and not (tmp_path / "a.zip").exists()


def test_a_part_file_is_opened_without_following_links(tmp_path):
    from motionlang.datasets.download import _open_part
    victim = tmp_path / "precious.txt"
    victim.write_bytes(b"keep me")
    link = tmp_path / "x.part"
    link.symlink_to(victim)
    for append in (True, False):                        # a link put there meanwhile
        with pytest.raises(DatasetError, match="replaced by a link"):
            _open_part(link, append=append)
    assert victim.read_bytes() == b"keep me"
    new = tmp_path / "new.part"
    with _open_part(new, append=False) as fh:
        fh.write(b"abc")
    assert new.read_bytes() == b"abc"

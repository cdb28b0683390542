"""Resumable download, checksum, offline and HTTP errors, safe extraction (local server)."""
from __future__ import annotations

import contextlib
import hashlib
import socket
import threading
import zipfile
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from motionlang.datasets.download import download_file, safe_extract
from motionlang.errors import DatasetError


class _Handler(BaseHTTPRequestHandler):
    """Serves ``server.payload`` at ``/data.zip``; behaviour set by ``server.mode``:
    ``"ok"`` (honours Range), ``"cut"`` (announces the full length, sends half, hangs up),
    ``"norange"`` (ignores Range, always 200)."""

    def log_message(self, *args):  # keep pytest output clean
        pass

    def do_GET(self):
        srv = self.server
        srv.requests.append((self.path, self.headers.get("Range")))
        if self.path != "/data.zip":
            self.send_error(404, "Not Found")
            return
        data, start = srv.payload, 0
        rng = self.headers.get("Range")
        if rng and srv.mode == "ok":
            start = int(rng.split("=")[1].split("-")[0])
            if start >= len(data):
                self.send_response(416)
                self.end_headers()
                return
            self.send_response(206)
            self.send_header("Content-Range", f"bytes {start}-{len(data) - 1}/{len(data)}")
        else:
            self.send_response(200)
        body = data[start:]
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if srv.mode == "cut":
            self.wfile.write(body[: len(body) // 2])
            self.wfile.flush()
            self.close_connection = True
            self.connection.shutdown(socket.SHUT_RDWR)
            return
        self.wfile.write(body)


@contextlib.contextmanager
def serve(payload: bytes, mode: str = "ok"):
    """A local HTTP server on a random port in a thread; yields it (``.url``, ``.mode``,
    ``.requests``) and shuts it down afterwards."""
    srv = ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
    srv.payload, srv.mode, srv.requests = payload, mode, []
    srv.url = f"http://127.0.0.1:{srv.server_address[1]}/data.zip"
    thread = threading.Thread(target=srv.serve_forever, daemon=True)
    thread.start()
    try:
        yield srv
    finally:
        srv.shutdown()
        srv.server_close()
        thread.join(5)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


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
    (tmp_path / "a.zip.part").write_bytes(b"x" * 1000)   # stale bytes that are no prefix
    with serve(PAYLOAD, mode="norange") as srv:
        download_file(srv.url, tmp_path / "a.zip")
        assert srv.requests[0][1] == "bytes=1000-"
    assert (tmp_path / "a.zip").read_bytes() == PAYLOAD


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

"""A local HTTP server for download tests (range requests, cut connections) and a free port."""
from __future__ import annotations

import contextlib
import socket
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer


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

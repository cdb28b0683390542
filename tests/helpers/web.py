"""A served app for the web tests: small packaged models, and HTTP calls that return the
status and the decoded body (errors included)."""
from __future__ import annotations

import contextlib
import json
import os
import urllib.error
import urllib.request
import uuid

import pytest

pytest.importorskip("fastapi", reason="motionlang serve needs the web extra")
pytest.importorskip("multipart", reason="motionlang serve needs the web extra")

#: the small packaged models (they load in a fraction of a second)
SMALL = {"model": ["l2m-procedural"], "describe_model": "m2l-procedural", "warm": False}


def call(url: str, data: bytes | None = None, headers: dict | None = None):
    """``(status, body)``: JSON decoded, anything else as bytes."""
    req = urllib.request.Request(url, data=data, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=60) as res:
            status, body, kind = res.status, res.read(), res.headers.get("content-type", "")
    except urllib.error.HTTPError as exc:
        status, body, kind = exc.code, exc.read(), exc.headers.get("content-type", "")
    return status, json.loads(body) if "json" in kind else body


def post_json(url: str, payload: dict):
    return call(url, json.dumps(payload).encode(), {"Content-Type": "application/json"})


def post_files(url: str, files: list[tuple[str, bytes]]):
    """A multipart upload of ``files`` (name, bytes) as the page sends them."""
    boundary = uuid.uuid4().hex
    parts = []
    for name, data in files:
        parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="files"; '
                     f'filename="{name}"\r\nContent-Type: application/octet-stream\r\n\r\n'
                     .encode() + data + b"\r\n")
    body = b"".join(parts) + f"--{boundary}--\r\n".encode()
    return call(url, body, {"Content-Type": f"multipart/form-data; boundary={boundary}"})


@contextlib.contextmanager
def served(folder, **options):
    """The app over the small models (``options``: more ``ServeOptions``) on a free port,
    run from ``folder`` (empty), which must stay empty; yields its URL."""
    from motionlang.web.app import running
    from motionlang.web.options import ServeOptions
    from motionlang.web.studio import Studio
    old = os.getcwd()
    os.chdir(folder)
    try:
        with running(Studio(ServeOptions(**{**SMALL, **options}))) as url:
            yield url
    finally:
        os.chdir(old)
    assert list(folder.iterdir()) == [], "the server wrote into its working folder"

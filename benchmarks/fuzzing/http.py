"""Fuzzing ``motionlang serve`` over HTTP: requests mutated from valid ones for every route,
sent one at a time over loopback, and what came back sorted into outcomes.

Every request starts from a valid one of its route (a sentence to generate, a motion file to
describe or take as a rig, a query, a span of an indexed take, a download of a generated
take) and gets 1-3 mutations: JSON fields dropped, added, or given values of another type,
extreme numbers, very long or odd strings, the JSON text itself edited at byte level;
uploaded files edited as the reader fuzzers edit them (:func:`.inputs.mutate`), renamed
(``../x``, no extension, another format's extension), split or joined, the multipart framing
broken; query parameters dropped, repeated or given odd values, paths with odd names; the
method, the media type, ``Host`` and ``Origin`` changed. Ids that the server hands out
(takes, rigs, indexed files) are collected as the run goes, so downloads and rigs reach the
code behind them rather than only "no such take".

:func:`outcome` says what an answer means: ``ok`` (2xx), ``refused`` (a 4xx with one line
of JSON ``{"error": ...}``), or a fault: ``server-error`` (5xx), ``bad-error`` (a 4xx whose
body is not one JSON line), ``foreign-served`` (a request with another site's ``Host`` or
``Origin`` answered with anything but its refusal, 400 or 403), ``hang`` (no answer within the time limit) and
``down`` (the connection refused or dropped). Used by ``benchmarks/fuzz_serve.py`` and
``tests/test_fuzz_serve.py``.
"""
from __future__ import annotations

import http.client
import json
import random
import time
import uuid
from dataclasses import dataclass, field
from urllib.parse import quote, urlsplit

from motionlang.web.same_site import SAFE_METHODS

from .edits import SPECIAL
from .inputs import mutate
from .sandbox import EXTENSIONS
from .seeds import seeds

FAULTS = ("server-error", "bad-error", "foreign-served", "hang", "down")
ROUTES = ("page", "static", "info", "generate", "describe", "rig", "search", "take",
          "export")
#: JSON values of every type, and strings that stress whoever reads them
ODD_VALUES: list = [None, True, False, 0, -1, 1, 2 ** 63, -(2 ** 63), 1e308, -1e308, 1e-320,
                    float("nan"), float("inf"), float("-inf"), 0.5, "", " ", "0", "-1",
                    "1e999", "nan", "x" * 10_000, "\u0000", "\ud800", "é" * 300, "../../etc",
                    "%s%n", [], [1, 2], {}, {"a": 1}, "<script>", "\n\r\t"]
#: query and path values: text only
ODD_TEXT = ["", " ", "0", "-1", "1", "-0", "1e308", "-1e308", "1e999", "nan", "NaN", "inf",
            "-inf", "9" * 400, "0x10", "1_000", "true", "null", "[]", "{}", "\x00", "%zz",
            "%", "..", "../../etc/passwd", "/etc/passwd", "é" * 100, "x" * 5000, "a,b",
            "<script>", "' OR 1=1 --", "\n"]
SENTENCES = ["a person walks forward", "someone waves with the right hand",
             "a person jumps", "a man runs and then sits down", "a person bows slowly"]
FOREIGN = "attacker.example"


@dataclass
class Request:
    """One HTTP request: ``route`` (one of :data:`ROUTES`), method, path with query,
    headers (without ``Host``: the server's own) and body; ``foreign``: the status it must
    get, coming from another site (400 for a foreign ``Host``, 403 for a cross-site
    ``Origin`` on a method that changes something), 0 if it does not."""

    route: str
    method: str
    path: str
    headers: dict[str, str] = field(default_factory=dict)
    body: bytes = b""
    foreign: int = 0


@dataclass
class Answer:
    status: int | None
    body: bytes
    seconds: float
    failure: str = ""     # why there is no status: "hang" or "down"


@dataclass
class Pools:
    """What the server has handed out so far, for requests that name it."""

    takes: list[str] = field(default_factory=lambda: ["1"])
    rigs: list[str] = field(default_factory=list)
    spans: list[tuple[str, float, float]] = field(default_factory=list)

    def learn(self, req: Request, answer: Answer) -> None:
        """Keep the ids of a successful answer (at most a few dozen of each)."""
        if answer.status != 200 or req.route not in ("generate", "rig", "search"):
            return
        try:
            got = json.loads(answer.body)
        except ValueError:
            return
        if req.route == "generate" and isinstance(got, dict) and "id" in got:
            _keep(self.takes, str(got["id"]))
        elif req.route == "rig" and isinstance(got, dict) and "id" in got:
            _keep(self.rigs, str(got["id"]))
        elif req.route == "search" and isinstance(got, list):
            for hit in got[:3]:
                _keep(self.spans, (hit["file"], hit["start"], hit["end"]))


def _keep(pool: list, item) -> None:
    if item not in pool:
        pool.append(item)
        del pool[:-32]


def upload_seeds(shared=None) -> list[list[tuple[str, bytes]]]:
    """Valid uploads: a BVH, an MMM ``.xml``, an AMC with its ASF, a MIT ``.mat``, a GLB
    (the readers' fuzzing seeds: hand-made, and real files cut short where ``shared``
    holds the data)."""
    out: list[list[tuple[str, bytes]]] = []
    for fmt in ("bvh", "mmm", "amc", "mit", "glb"):
        for data, skeleton in seeds(fmt, shared)[:3]:
            files = [(f"take{EXTENSIONS[fmt]}", data)]
            if skeleton is not None:
                files.append(("take.asf", skeleton))
            out.append(files)
    return out


class Fuzzer:
    """Mutated requests, reproducible from ``seed``; ``uploads`` from :func:`upload_seeds`,
    ``queries``: plain-word searches that find something in the server's index."""

    def __init__(self, seed: int, uploads: list[list[tuple[str, bytes]]],
                 models: list[str], queries: list[str] | None = None):
        self.rng = random.Random(seed)
        self.uploads = uploads
        self.models = models
        self.queries = queries or ["a person walks", "someone sits down", "jumping"]
        self.pools = Pools()

    # ---------------------------------------------------------------- one request
    def next(self) -> Request:
        rng = self.rng
        route = rng.choices(ROUTES, weights=[1, 2, 1, 8, 8, 5, 4, 3, 4])[0]
        req = getattr(self, "_" + route)()
        if rng.random() < 0.03:
            req.method = rng.choice(["GET", "POST", "PUT", "DELETE", "PATCH", "OPTIONS"])
        if rng.random() < 0.04:
            req.headers["Host"], req.foreign = rng.choice([FOREIGN, FOREIGN + ":8000",
                                                           "127.0.0.2", "", "[::2]"]), 400
        elif req.method not in SAFE_METHODS and rng.random() < 0.06:
            req.headers["Origin"], req.foreign = rng.choice(
                [f"http://{FOREIGN}", "null", f"http://127.0.0.1.{FOREIGN}"]), 403
        if rng.random() < 0.03 and "Content-Type" in req.headers:
            req.headers["Content-Type"] = rng.choice(
                ["text/plain", "application/json", "multipart/form-data",
                 "application/x-www-form-urlencoded", "", "multipart/form-data; boundary="])
        return req

    def _odd(self) -> object:
        return self.rng.choice(ODD_VALUES)

    def _text(self) -> str:
        rng = self.rng
        return rng.choice(ODD_TEXT) if rng.random() < 0.5 \
            else rng.choice(SPECIAL).decode("utf-8", "replace")

    def _query(self, params: dict[str, str]) -> str:
        """``params`` (a valid query) with 0-3 of them dropped, repeated, given odd values,
        or joined by an unknown one; percent-encoded."""
        rng = self.rng
        items = list(params.items())
        for _ in range(rng.randrange(4)):
            op = rng.randrange(4)
            if op == 0 and items:
                items.pop(rng.randrange(len(items)))
            elif op == 1 and items:
                items[rng.randrange(len(items))] = (items[rng.randrange(len(items))][0],
                                                    self._text())
            elif op == 2 and items:
                items.append(items[rng.randrange(len(items))])
            else:
                items.append((rng.choice(["x", "k", "q", "", "limit"]), self._text()))
        return "&".join(f"{quote(k, safe='')}={quote(v, safe='%')}" for k, v in items)

    def _page(self) -> Request:
        path = self.rng.choice(["/", "/index.html", "//", "/?x=1", "/api", "/api/"])
        return Request("page", "GET", path)

    def _static(self) -> Request:
        name = self.rng.choice(["app.js", "viewer.js", "style.css", "index.html", "..%2Fapp.py",
                                "%2e%2e/options.py", "", "x" * 300, "app.js%00.css"])
        return Request("static", "GET", f"/static/{name}")

    def _info(self) -> Request:
        return Request("info", "GET", "/api/info?" + self._query({}))

    def _generate(self) -> Request:
        rng = self.rng
        body: dict = {"text": rng.choice(SENTENCES), "seconds": rng.choice([1, 2, 3]),
                      "seed": rng.randrange(100)}
        if rng.random() < 0.5:
            body["model"] = rng.choice(self.models)
        if rng.random() < 0.3:
            body["method"] = rng.choice(["sample", "beam", "mean"])
        if self.pools.rigs and rng.random() < 0.3:
            body["rig"] = rng.choice(self.pools.rigs)
        keys = ["text", "model", "seconds", "seed", "method", "rig", "extra"]
        for _ in range(1 + rng.randrange(3)):
            op = rng.randrange(4)
            key = rng.choice(keys)
            if op == 0:
                body.pop(key, None)
            elif op == 1:
                body[key] = self._odd()
            elif op == 2 and key == "text":
                body["text"] = " ".join(rng.choice(SENTENCES).split()[::-1]) + self._text()
            elif op == 3 and key == "seconds":
                body["seconds"] = rng.choice([0, 0.01, 0.04, 59.9, 60, 60.01, 1e9, -5])
        data = json.dumps(body).encode()   # NaN and Infinity as JavaScript writes them
        if rng.random() < 0.2:
            data = mutate(data, rng.randrange)
        if rng.random() < 0.05:
            data = json.dumps([body]).encode() if rng.random() < 0.5 else b""
        return Request("generate", "POST", "/api/generate",
                       {"Content-Type": "application/json"}, data)

    def _files(self) -> list[tuple[str, bytes]]:
        rng = self.rng
        files = [(n, d) for n, d in rng.choice(self.uploads)]
        if rng.random() < 0.8:
            i = rng.randrange(len(files))
            name, data = files[i]
            fmt = {".xml": "mmm", ".mat": "mit"}.get(name[name.rfind("."):], "")
            files[i] = (name, mutate(data, rng.randrange, fmt))
        if rng.random() < 0.25:
            i = rng.randrange(len(files))
            files[i] = (rng.choice(["../../x.bvh", "take", ".bvh", "a.AMC", "take.asf",
                                    "take.json", "take.glb", "take.xml", "t\u00e9.bvh",
                                    "x" * 300 + ".bvh", "", "con.bvh", "take.bvh.exe"]),
                        files[i][1])
        if rng.random() < 0.1:
            files = rng.choice([[], files + files, files[:1], files + [("map.json", b"{}")],
                                files + [("map.json", b'{"Hips": 7}')]])
        return files

    def _multipart(self, route: str) -> Request:
        rng = self.rng
        boundary = uuid.UUID(int=rng.getrandbits(128)).hex
        field = "files" if rng.random() > 0.05 else rng.choice(["file", "", "files[]"])
        parts = [f'--{boundary}\r\nContent-Disposition: form-data; name="{field}"; '
                 f'filename="{name}"\r\nContent-Type: application/octet-stream\r\n\r\n'
                 .encode("utf-8", "replace") + data + b"\r\n" for name, data in self._files()]
        body = b"".join(parts) + f"--{boundary}--\r\n".encode()
        if rng.random() < 0.05:
            body = body[:rng.randrange(len(body) + 1)]
        ctype = f"multipart/form-data; boundary={boundary}"
        if rng.random() < 0.03:
            ctype = "multipart/form-data; boundary=" + rng.choice(["", "x" * 200, "\u00e9"])
        return Request(route, "POST", f"/api/{route}", {"Content-Type": ctype}, body)

    def _describe(self) -> Request:
        return self._multipart("describe")

    def _rig(self) -> Request:
        return self._multipart("rig")

    def _search(self) -> Request:
        rng = self.rng
        params = {"q": rng.choice(self.queries), "k": str(rng.choice([1, 5, 10]))}
        if rng.random() < 0.3:
            params["where"] = rng.choice(["walk", "sit", "stand", "jump", "nothing"])
        if rng.random() < 0.3:
            params["min_duration"] = rng.choice(["1", "2.5", "10", "1s", "-1"])
        return Request("search", "GET", "/api/search?" + self._query(params))

    def _take(self) -> Request:
        rng = self.rng
        file, start, end = rng.choice(self.pools.spans) if self.pools.spans \
            else ("walk.bvh", 0.0, 1.0)
        params = {"file": file, "start": f"{start:g}", "end": f"{end:g}"}
        return Request("take", "GET", "/api/take?" + self._query(params))

    def _export(self) -> Request:
        rng = self.rng
        take = rng.choice(self.pools.takes) if rng.random() < 0.85 else self._text()
        fmt = rng.choice(["bvh", "glb", "mp4"]) if rng.random() < 0.85 else \
            rng.choice(["npz", "BVH", "", "bvh.bvh", "..", "gltf", "fbx"])
        params = {"rig": rng.choice(self.pools.rigs)} \
            if self.pools.rigs and rng.random() < 0.4 else {}
        return Request("export", "GET", f"/api/export/{quote(take, safe='')}.{quote(fmt)}?"
                       + self._query(params))


def send(url: str, req: Request, timeout: float) -> Answer:
    """``req`` sent to the server at ``url`` on a new connection."""
    parts = urlsplit(url)
    conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=timeout)
    t0 = time.perf_counter()
    try:
        conn.putrequest(req.method, req.path, skip_host=True, skip_accept_encoding=True)
        conn.putheader("Host", req.headers.get("Host", parts.netloc))
        for name, value in req.headers.items():
            if name != "Host":
                conn.putheader(name, value.encode("utf-8", "replace"))
        conn.putheader("Content-Length", str(len(req.body)))
        conn.endheaders(req.body)
        res = conn.getresponse()
        body = res.read()
        return Answer(res.status, body, time.perf_counter() - t0)
    except TimeoutError:
        return Answer(None, b"", time.perf_counter() - t0, "hang")
    except (ConnectionError, http.client.HTTPException, OSError) as exc:
        return Answer(None, str(exc).encode(), time.perf_counter() - t0, "down")
    finally:
        conn.close()


def outcome(req: Request, answer: Answer) -> str:
    """What ``answer`` to ``req`` means (module docstring)."""
    if answer.status is None:
        return answer.failure
    if req.foreign:
        return "refused" if answer.status == req.foreign else "foreign-served"
    if answer.status >= 500:
        return "server-error"
    if answer.status < 400:
        return "ok"
    try:
        got = json.loads(answer.body)
    except ValueError:
        return "bad-error"
    ok = isinstance(got, dict) and isinstance(got.get("error"), str) \
        and got["error"].strip() and "\n" not in got["error"] \
        and "Traceback" not in got["error"]
    return "refused" if ok else "bad-error"

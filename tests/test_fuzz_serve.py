"""A short HTTP fuzz of ``motionlang serve`` (``benchmarks/fuzzing/http.py``; the benchmark
``benchmarks/fuzz_serve.py`` sends thousands): every answer is a 2xx or one line of JSON
with a 4xx, a foreign Host or cross-site Origin is refused, the server stays up and writes
nothing into its working folder; and the faults that fuzzing found, pinned."""
from __future__ import annotations

import sys
from collections import Counter

import pytest

import motionlang.api as ml
from helpers.data import ROOT, SHARED
from helpers.rigs import RIGS, write
from helpers.web import call, post_files, post_json, served
from motionlang.errors import MotionlangError

sys.path.insert(0, str(ROOT / "benchmarks"))  # the fuzzing package lives beside its benchmark
from fuzzing.http import FAULTS, Answer, Fuzzer, Request, outcome, send, upload_seeds  # noqa: E402

REQUESTS = 150


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """The app on a free port, run from an empty folder that must stay empty."""
    with served(tmp_path_factory.mktemp("cwd"), max_upload_mb=2) as url:
        yield url


def test_mutated_requests_get_an_answer_or_one_line_never_a_fault(server):
    fuzzer = Fuzzer(3, upload_seeds(SHARED if SHARED.is_dir() else None), ["l2m-procedural"])
    kinds: Counter = Counter()
    faults = []
    for i in range(REQUESTS):
        req = fuzzer.next()
        answer = send(server, req, timeout=60)
        kind = outcome(req, answer)
        kinds[kind] += 1
        fuzzer.pools.learn(req, answer)
        if kind in FAULTS:
            faults.append(f"#{i} {req.method} {req.path[:80]} -> {answer.status}: "
                          f"{answer.body[:120]!r}")
    assert faults == []
    assert kinds["ok"] >= 10 and kinds["refused"] >= 10, kinds   # both kinds were reached
    assert len(fuzzer.pools.takes) > 1   # downloads named takes that exist
    assert send(server, Request("info", "GET", "/api/info"), 60).status == 200


def test_the_outcomes_tell_a_fault_from_a_refusal():
    plain, foreign = Request("info", "GET", "/x"), Request("info", "GET", "/x", foreign=400)
    assert outcome(plain, Answer(200, b"{}", 0)) == "ok"
    assert outcome(plain, Answer(400, b'{"error": "one line"}', 0)) == "refused"
    assert outcome(plain, Answer(500, b'{"error": "internal"}', 0)) == "server-error"
    assert outcome(plain, Answer(400, b"Traceback (most recent call last)", 0)) == "bad-error"
    assert outcome(plain, Answer(400, b'{"error": "two\\nlines"}', 0)) == "bad-error"
    assert outcome(foreign, Answer(200, b"{}", 0)) == "foreign-served"
    assert outcome(foreign, Answer(400, b'{"error": "not this server"}', 0)) == "refused"
    assert outcome(plain, Answer(None, b"", 60, "hang")) == "hang"


def test_a_span_that_is_not_a_number_of_seconds_is_one_line():
    motion = ml.generate("a person walks", "l2m-procedural", max_frames=20)
    for start, end in ((float("nan"), 1.0), (0.0, float("inf")), (1e308, 2.0)):
        with pytest.raises(MotionlangError, match="finite number of seconds"):
            motion.between(start, end)


def test_an_upload_with_a_very_long_name_is_read(server, tmp_path):
    rig = write(RIGS["cmu-bvh"], tmp_path, T=4)
    status, got = post_files(server + "api/rig", [("x" * 300 + ".bvh", rig.read_bytes())])
    assert status == 200, got
    assert got["name"] == "x" * 100
    assert call(server + "api/info")[0] == 200


def test_a_take_of_a_sentence_in_other_letters_downloads(server):
    status, view = post_json(server + "api/generate", {"text": "a person walks ١٢ é", "seconds": 1})
    assert status == 200, view
    status, bvh = call(server + f"api/export/{view['id']}.bvh")
    assert status == 200 and bvh.startswith(b"HIERARCHY")

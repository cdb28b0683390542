"""``describe`` on whole libraries and long takes (library/describe.py, library/timeline.py,
library/bank.py): a folder in one run with a bad file among the good, workers, a timeline
of a take that does two things, sentences from a bank, and the Python API against the CLI.

The packaged models describe (m2l) and embed (twostream): the tests read what a user gets.
"""
from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest

import motionlang as ml
from helpers.rigs import RIGS, write
from motionlang.cli.main import main
from motionlang.datasets.synth.compose import build_motion, random_style
from motionlang.datasets.synth.corpus import generate_sample
from motionlang.datasets.synth.spec import Primitive
from motionlang.errors import MotionlangError
from motionlang.library.bank import read_bank
from motionlang.library.describe import Describer, motion_paths
from motionlang.library.timeline import action_of, merge_windows
from motionlang.library.windows import Window

WIDTH = ["-w", "2"]
SEGMENT = re.compile(r"^(\d+\.\d)-(\d+\.\d) s  (.+)$")


@pytest.fixture(scope="module")
def library(tmp_path_factory) -> Path:
    """Three procedural takes (one in a sub-folder), a truncated BVH, and a note that is
    not a motion file."""
    root = tmp_path_factory.mktemp("library")
    (root / "more").mkdir()
    for i, where in enumerate(("a.bvh", "b.xml", "more/c.bvh")):
        ml.write_motion(generate_sample(7, i).motion, root / where)
    text = (root / "a.bvh").read_text().splitlines()
    (root / "more" / "broken.bvh").write_text("\n".join(text[:len(text) // 3]) + "\n")
    (root / "notes.txt").write_text("takes of the first session\n")
    return root


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _run(argv: list[str], capsys) -> str:
    assert main(argv) == 0, capsys.readouterr().err
    return capsys.readouterr().out


@pytest.fixture(scope="module")
def described(library, tmp_path_factory) -> list[str]:
    """The lines of ``describe LIBRARY -o captions.jsonl`` (one process)."""
    out = tmp_path_factory.mktemp("out") / "captions.jsonl"
    assert main(["describe", str(library), "-o", str(out), *WIDTH, "--threads", "1"]) == 0
    return out.read_text().splitlines()


@pytest.fixture(scope="module")
def long_take(tmp_path_factory) -> tuple[Path, list[Primitive]]:
    """A procedural take that walks, then squats (one continuous motion), as a BVH."""
    rng = np.random.default_rng(3)
    program = [Primitive("walk", count=6, direction="forward", speed="normal"),
               Primitive("squat", count=3)]
    motion, done, _ = build_motion(program, random_style(rng), rng)
    path = tmp_path_factory.mktemp("take") / "walk_then_squat.bvh"
    ml.write_motion(motion, path)
    return path, done


def test_a_folder_gives_one_line_per_motion_file_and_the_reason_of_a_bad_one(library,
                                                                            described):
    records = [json.loads(line) for line in described]
    files = [Path(r["file"]).relative_to(library).as_posix() for r in records]
    assert files == ["a.bvh", "b.xml", "more/broken.bvh", "more/c.bvh"]   # no notes.txt
    bad = records[2]
    assert set(bad) == {"file", "error"} and "broken.bvh" in bad["error"]
    assert "\n" not in bad["error"]
    for r in records[:2] + records[3:]:   # at most W: a model sentence that repeats itself
        assert 1 <= len(r["sentences"]) <= 2   # or contradicts the body is left out
        # a model's log P is negative; the grounded sentence has none (null)
        assert all(s["text"] and (s["log_p"] is None or s["log_p"] < 0)
                   for s in r["sentences"])


def test_an_output_in_a_folder_not_made_yet_is_written_there(library, described, tmp_path,
                                                               capsys):
    out = tmp_path / "new" / "folder" / "captions.jsonl"   # as every other command's -o
    _run(["describe", str(library), "-o", str(out), *WIDTH, "--threads", "1"], capsys)
    assert out.read_text().splitlines() == described
    assert sorted(p.name for p in out.parent.iterdir()) == ["captions.jsonl"]


def test_two_workers_write_the_same_lines_as_one(library, described, tmp_path, capsys):
    out = tmp_path / "captions.jsonl"
    printed = _run(["describe", str(library / "more"), str(library / "a.bvh"),
                    str(library / "b.xml"), "-o", str(out), *WIDTH, "--workers", "2",
                    "--threads", "1"], capsys)
    assert "3 of 4 files described; 1 could not be" in printed
    by_file = {json.loads(line)["file"]: line for line in out.read_text().splitlines()}
    assert sorted(by_file.values()) == sorted(described)


def test_a_take_that_walks_then_squats_is_two_segments_in_order(long_take, capsys):
    path, done = long_take
    lines = _run(["describe", str(path), "--segments", *WIDTH], capsys).splitlines()
    segments = [SEGMENT.match(line).groups() for line in lines]
    assert len(segments) >= 2, lines
    starts, ends = [float(s) for s, _, _ in segments], [float(e) for _, e, _ in segments]
    assert starts[0] == 0.0 and starts[1:] == ends[:-1]    # the segments tile the take
    assert ends[-1] == pytest.approx(ml.read_motion(path).duration, abs=0.1)
    actions = [action_of(text) for _, _, text in segments]
    # standing still before and after the squats is said where the body does it
    moving = [a for a in actions if a not in ("stand", "wait")]
    assert moving[0] == "walk" and moving[-1] == "squat", lines
    squat_starts = done[1].start / 100   # frames at 100 Hz
    walk_ends = [e for e, a in zip(ends, actions) if a == "walk"]
    assert abs(walk_ends[-1] - squat_starts) <= 1.5, (lines, squat_starts)


def test_the_api_gives_what_the_command_line_writes(library, described, long_take, capsys):
    assert [json.dumps(r, ensure_ascii=False) for r in
            ml.describe_many(library, width=2)] == described
    path, _ = long_take
    printed = _run(["describe", str(path), "--segments", *WIDTH, "--json"], capsys)
    segments = ml.timeline(path, width=2)
    # a segment the grounded analysis says has no model score: null
    assert [{"start": s.start, "end": s.end, "text": s.text,
             "log_p": None if math.isnan(s.score) else round(s.score, 4)}
            for s in segments] == json.loads(printed)


def test_sentences_from_a_bank(library, tmp_path, capsys, private_cache):
    bank = tmp_path / "bank.txt"
    sentences = ["a person walks forward", "someone squats down", "a person waves a hand",
                 "A person walks forward.", "", "a person jumps"]
    bank.write_text("\n".join(sentences) + "\n")
    assert read_bank(bank) == [s for s in sentences[:3]] + ["a person jumps"]  # once each
    hyps = json.loads(_run(["describe", str(library / "a.bvh"), "--bank", str(bank), "-w",
                            "3", "--json"], capsys))
    assert [h["rank"] for h in hyps] == [1, 2, 3]
    assert all(h["text"] in sentences and -1 <= h["cos"] <= 1 for h in hyps)
    assert hyps[0]["cos"] >= hyps[1]["cos"] >= hyps[2]["cos"]
    assert len(list(private_cache.glob("bank-*.npz"))) == 1   # embedded once, then read
    out = tmp_path / "bank.jsonl"
    _run(["describe", str(library), "--bank", str(bank), "-w", "1", "-o", str(out)], capsys)
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert [len(r.get("sentences", [])) for r in records] == [1, 1, 0, 1]
    assert ml.describe_many(library, bank=str(bank), width=1) == records


def test_bank_files_of_every_kind(tmp_path):
    (tmp_path / "captions.csv").write_text('file,text\na.bvh,"a person walks"\n'
                                           'b.bvh,a person sits\na.bvh,a person walks\n')
    (tmp_path / "captions.jsonl").write_text('{"file": "a.bvh", "text": "a person bows"}\n')
    (tmp_path / "kit.json").write_text(json.dumps(
        {"00001": {"annotations": [{"text": "A human waves."}]},
         "M00001": {"annotations": [{"text": "A human waves."}, {"text": "He kicks."}]}}))
    assert read_bank(tmp_path / "captions.csv") == ["a person walks", "a person sits"]
    assert read_bank(tmp_path / "captions.jsonl") == ["a person bows"]
    assert read_bank(tmp_path / "kit.json") == ["A human waves.", "He kicks."]
    (tmp_path / "empty.txt").write_text("\n\n")
    with pytest.raises(MotionlangError, match="no sentences"):
        read_bank(tmp_path / "empty.txt")
    (tmp_path / "no_text.json").write_text(json.dumps({"k1": {"annotations": [{"t": "x"}]}}))
    with pytest.raises(MotionlangError, match="no_text.json: entry 'k1', annotation 0 has "
                                              "no 'text'"):
        read_bank(tmp_path / "no_text.json")
    (tmp_path / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(MotionlangError, match="deep.json: JSON nested deeper than 64"):
        read_bank(tmp_path / "deep.json")


def test_windows_merge_where_their_actions_agree():
    spans = [Window(s, s + 3.0) for s in range(6)]            # a 9 s take
    labels = [("a person walks forward", -2.0), ("a man walks slowly", -3.0),
              ("a person walks forward", -4.0), ("a person does 3 jumps", -1.0),
              ("3 jumps", -5.0), ("the person waves with the left hand", -2.0)]
    by_action = merge_windows(spans, labels, end=9.0)
    assert [(s.start, s.end, s.text, s.windows) for s in by_action] == [
        (0.0, 4.0, "a person walks forward", 3), (4.0, 6.0, "a person does 3 jumps", 2),
        (6.0, 9.0, "the person waves with the left hand", 1)]
    assert by_action[0].score == pytest.approx(-3.0)   # the mean of its two windows
    by_sentence = merge_windows(spans, labels, end=9.0, merge="sentence", bridge=0)
    assert len(by_sentence) == 6
    flicker = [labels[0], labels[3], labels[1]]       # walk, a window of jumps, walk
    assert [(s.text, s.windows) for s in merge_windows(spans[:3], flicker)] == [
        ("a person walks forward", 3)]                # (ties: the higher score)
    assert len(merge_windows(spans[:3], flicker, bridge=0)) == 3
    assert action_of("waves with the right hand") != action_of("waves with the left hand")


@pytest.mark.parametrize(("options", "message"), [
    (["--segments", "--hop", "4"], "--hop (4) must not exceed --window (3)"),
    (["--window", "0"], "--window must be a finite number > 0"),
    (["--workers", "0"], "--workers must be an integer >= 1"),
    (["--bank", "{tmp}/none.txt"], "none.txt: sentence bank not found"),
    (["--bank", "{tmp}/bank.txt", "--model", "m2l"], "m2l.pt: a model of kind m2l, not"),
])
def test_bad_options_are_one_line_and_write_nothing(library, tmp_path, capsys, options,
                                                    message):
    (tmp_path / "bank.txt").write_text("a person walks\n")
    argv = ["describe", str(library), "-o", str(tmp_path / "o.jsonl"),
            *(o.format(tmp=tmp_path) for o in options)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "o.jsonl").exists()


def test_a_missing_input_is_named_before_anything_is_written(library, tmp_path, capsys):
    out = tmp_path / "o.jsonl"
    assert main(["describe", str(library), str(tmp_path / "gone"), "-o", str(out)]) == 2
    assert "gone: no such file or folder" in capsys.readouterr().err
    assert not out.exists()


def test_an_interrupted_run_keeps_what_it_did_and_the_same_command_goes_on(library, described,
                                                                         tmp_path, capsys,
                                                                         monkeypatch):
    out = tmp_path / "captions.jsonl"
    argv = ["describe", str(library), "-o", str(out), *WIDTH, "--threads", "1"]
    real, seen = Describer.record, []

    def stop_at_the_third(self, path):
        seen.append(path)
        if len(seen) == 3:
            raise KeyboardInterrupt
        return real(self, path)

    monkeypatch.setattr(Describer, "record", stop_at_the_third)
    assert main(argv) == 130                            # Ctrl-C
    partial = tmp_path / "captions.jsonl.partial"
    assert not out.exists() and len(partial.read_text().splitlines()) == 1 + 2
    monkeypatch.setattr(Describer, "record", real)
    again = []
    monkeypatch.setattr(Describer, "record", lambda self, p: again.append(p) or real(self, p))
    assert main(argv) == 0
    assert len(again) == 2                              # only the two not done before
    assert out.read_text().splitlines() == described and not partial.exists()
    # a partial of another command is not gone on from
    partial.write_text(json.dumps({"motionlang describe": {"other": 1}}) + "\n")
    assert main(argv) == 0 and out.read_text().splitlines() == described
    capsys.readouterr()


class Dying(Describer):
    """A describer whose worker process dies on one file, as one killed would."""

    def record(self, path):
        if Path(path).name == "c.bvh":
            os._exit(3)
        return super().record(path)


def test_a_worker_that_dies_is_one_line_and_what_was_done_is_kept(library, tmp_path):
    from motionlang.library.describe import describe_run
    from motionlang.library.options import DescribeOptions
    run = describe_run([library / "a.bvh", library / "more"], None,
                       DescribeOptions(workers=2, width=2))
    run.describer.__class__ = Dying
    out = tmp_path / "o.jsonl"
    with pytest.raises(MotionlangError, match="worker process died.*run the same command "
                                              "again"):
        run.write(out)
    assert not out.exists() and (tmp_path / "o.jsonl.partial").is_file()


def test_a_folder_that_cannot_be_listed_is_named_not_left_out_silently(tmp_path,
                                                                       monkeypatch):
    (tmp_path / "lib" / "locked").mkdir(parents=True)
    ml.write_motion(ml.read_motion(write(RIGS["mixamo"], tmp_path, T=4)), tmp_path / "lib" /
                    "a.bvh")
    real = os.scandir

    def refuse(path):   # root lists any folder: the refusal is made by hand
        if str(path).endswith("locked"):
            raise PermissionError(13, "Permission denied")
        return real(path)

    monkeypatch.setattr("motionlang.library.scan.os.scandir", refuse)
    with pytest.warns(UserWarning, match=r"locked/: left out: cannot list this folder: "
                                         "Permission denied"):
        assert [p.name for p in motion_paths([tmp_path / "lib"])] == ["a.bvh"]


def test_a_long_take_shows_the_progress_of_its_timeline(tmp_path, monkeypatch):
    import motionlang.library.describe as describe_module
    from motionlang.library.options import DescribeOptions
    shown = []

    def recorded(items, **kw):
        shown.append((len(items), kw["unit"], kw["desc"]))
        return items

    monkeypatch.setattr(describe_module, "progress", recorded)
    path = write(RIGS["mixamo"], tmp_path, "walker", T=120)
    run = describe_module.describe_run([path], "m2l-procedural",
                                       DescribeOptions(segments=True, width=1))
    run.describer.record(path)
    assert shown == []                                  # 4 s: nothing to show
    monkeypatch.setattr(describe_module, "LONG_TAKE_S", 1.0)
    record = run.describer.record(path)
    assert shown and shown[0][1] in ("segments", "windows") and "walker" in shown[0][2]
    assert all(s["start"] == round(s["start"], 3) for s in record["segments"])

"""Writers of dataset folders refuse to write over what is there (issue 44, item 0):
``data synth`` over a corpus, ``data split`` over split files, ``data export-h3d`` into
a non-empty folder: exit 2, one line, every existing file byte-identical."""
from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from motionlang.cli.main import main


def digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.iterdir()) if p.is_file()}


def one_line(capsys, *needles: str) -> None:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    for n in needles:
        assert n in err, err


@pytest.fixture
def corpus(tmp_path) -> Path:
    out = tmp_path / "corpus"
    assert main(["data", "synth", "--out", str(out), "--n", "2", "--workers", "1"]) == 0
    return out


def test_synth_over_a_corpus_is_refused(corpus, capsys):
    before = digests(corpus)
    assert main(["data", "synth", "--out", str(corpus), "--n", "2", "--seed", "9",
                 "--workers", "1"]) == 2
    one_line(capsys, "not empty", "--overwrite", "--start")
    assert digests(corpus) == before
    # extending from where it ends is fine; from inside it is a clash
    assert main(["data", "synth", "--out", str(corpus), "--n", "1", "--start", "1",
                 "--workers", "1"]) == 2
    one_line(capsys, "already holds 00002_annotations.json")
    assert digests(corpus) == before
    assert main(["data", "synth", "--out", str(corpus), "--n", "1", "--start", "2",
                 "--workers", "1"]) == 0
    assert (corpus / "00003_mmm.xml").is_file()
    assert {k: v for k, v in digests(corpus).items() if k in before} == before


def test_synth_overwrite_replaces(corpus):
    before = digests(corpus)
    assert main(["data", "synth", "--out", str(corpus), "--n", "2", "--seed", "9",
                 "--workers", "1", "--overwrite"]) == 0
    assert digests(corpus) != before


def test_split_refuses_to_replace_split_files(corpus, tmp_path, capsys):
    out = tmp_path / "splits"
    assert main(["data", "split", str(corpus), "--out", str(out), "--fractions", "0.5",
                 "0.5"]) == 0
    before = digests(out)
    assert main(["data", "split", str(corpus), "--out", str(out), "--fractions", "0.5",
                 "0.5", "--seed", "3"]) == 2
    one_line(capsys, "already holds test.txt, train.txt", "--overwrite")
    assert digests(out) == before
    assert main(["data", "split", str(corpus), "--out", str(out), "--fractions", "0.5",
                 "0.5", "--seed", "3", "--overwrite"]) == 0


def test_export_h3d_refuses_a_non_empty_folder_before_reading(tmp_path, capsys):
    out = tmp_path / "h3d"
    out.mkdir()
    (out / "mine.txt").write_text("x")
    assert main(["data", "export-h3d", "--data", str(tmp_path / "absent"), "--out",
                 str(out)]) == 2
    one_line(capsys, "not empty (mine.txt)")
    assert digests(out) == {"mine.txt": hashlib.sha256(b"x").hexdigest()}

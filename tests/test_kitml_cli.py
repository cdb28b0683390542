"""``motionlang data download / info / split`` end to end against a local server."""
from __future__ import annotations

import json

from helpers.data import shared_file
from helpers.http_server import free_port, serve
from helpers.kitml import build_release
from motionlang.cli.main import main


def test_data_cli(tmp_path, capsys):
    release = build_release(shared_file("kitml/00001_mmm.xml").read_bytes())
    with serve(release) as srv:
        assert main(["data", "download", "kitml", "--dest", str(tmp_path / "d"),
                     "--url", srv.url]) == 0
    root = capsys.readouterr().out.strip()
    assert root.endswith("kitml")

    assert main(["data", "info", str(tmp_path / "d"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["all"]["motions"], info["all"]["annotations"]) == (3, 3)
    assert (info["kept"]["motions"], info["kept"]["annotations"]) == (2, 2)
    assert info["kept"]["without_annotations"] == 1
    assert info["all"]["duration_s"]["max"] == 31.0

    assert main(["data", "info", root]) == 0
    text = capsys.readouterr().out
    assert "motions 3" in text and "< 30 s: motions 2" in text

    out = tmp_path / "splits"
    assert main(["data", "split", root, "--fractions", "0.5", "0.5", "--seed", "1",
                 "--out", str(out)]) == 0
    ids = sorted((out / "train.txt").read_text().split() + (out / "test.txt").read_text().split())
    assert ids == ["00001", "00007"]


def test_data_cli_errors_are_one_line(tmp_path, capsys):
    url = f"http://127.0.0.1:{free_port()}/x.zip"
    assert main(["data", "download", "kitml", "--dest", str(tmp_path), "--url", url]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("motionlang data: error:") and url in err and "\n" not in err
    assert main(["data", "info", str(tmp_path / "nowhere")]) == 2
    assert "not found" in capsys.readouterr().err
    assert main(["data", "split", str(tmp_path), "--fractions", "0.9", "0.9", "--out",
                 str(tmp_path / "o")]) == 2

"""Sidecar inputs (issue 44, item 3): only regular files opened, JSON read with depth,
number and size bounds, no control characters in names and captions, caption and
vocabulary sizes under the limits, an unterminated quote named by its line, a UTF-8 BOM
accepted in every caption and joint-map file."""
from __future__ import annotations

import json
import os

import pytest

from motionlang.datasets.custom import read_captions
from motionlang.datasets.text import Vocabulary
from motionlang.errors import DatasetError, MotionlangError
from motionlang.features.joint_map import KIT21_NAMES, load_joint_map
from motionlang.formats import read_motion
from motionlang.utils import sidecar

fifo_only = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")


def _joint_map() -> dict:
    return {"name": "mine", "joints": {k: f"j_{k}" for k in KIT21_NAMES}}


@fifo_only
@pytest.mark.parametrize("reader", ["joint map", "captions", "asf", "json"])
def test_a_fifo_is_refused_by_name_without_blocking(tmp_path, reader):
    fifo = tmp_path / ("x.csv" if reader == "captions" else "x.asf" if reader == "asf"
                       else "x.json")
    os.mkfifo(fifo)
    read = {"joint map": load_joint_map, "captions": read_captions,
            "json": sidecar.load_json,
            "asf": lambda p: read_motion(tmp_path / "x.amc", skeleton=p)}[reader]
    (tmp_path / "x.amc").write_text(":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n")
    with pytest.raises(MotionlangError, match="FIFO") as err:
        read(fifo)
    assert str(fifo) in str(err.value)


def test_a_folder_and_a_device_are_refused_by_name(tmp_path):
    with pytest.raises(MotionlangError, match="is a folder"):
        sidecar.load_json(tmp_path)
    if os.path.exists("/dev/zero"):
        with pytest.raises(MotionlangError, match="character device"):
            load_joint_map("/dev/zero")


@pytest.mark.parametrize("text,why", [
    ("[" * 200_000 + "]" * 200_000, "nested deeper than"),
    ('{"a": ' + "7" * 5000 + "}", "5000 digits"),
    ('{"a": 1e999}', "not finite"),
    ('{"a": NaN}', "NaN"),
])
def test_bounded_json_is_one_line(tmp_path, text, why):
    for name in ("joint_map.json", "captions.jsonl"):
        path = tmp_path / name
        path.write_text(text)
        read = load_joint_map if name.endswith(".json") else read_captions
        with pytest.raises(MotionlangError, match=why) as err:
            read(path)
        assert str(path) in str(err.value) and "\n" not in str(err.value)


def test_json_over_the_size_limit_is_refused(tmp_path, monkeypatch):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(_joint_map()))
    monkeypatch.setenv("MOTIONLANG_MAX_JSON_BYTES", "100")
    with pytest.raises(MotionlangError, match="MOTIONLANG_MAX_JSON_BYTES"):
        load_joint_map(path)


def test_a_bom_is_accepted_in_every_caption_and_joint_map_file(tmp_path):
    (tmp_path / "c.csv").write_text("\ufefffile,text\na.bvh,walks\n", encoding="utf-8")
    (tmp_path / "c.jsonl").write_text('\ufeff{"file": "a.bvh", "text": "walks"}\n',
                                      encoding="utf-8")
    (tmp_path / "m.json").write_text("\ufeff" + json.dumps(_joint_map()), encoding="utf-8")
    assert read_captions(tmp_path / "c.csv") == [(2, "a.bvh", "walks")]
    assert read_captions(tmp_path / "c.jsonl") == [(1, "a.bvh", "walks")]
    assert load_joint_map(tmp_path / "m.json")["joints"]["root"] == "j_root"


@pytest.mark.parametrize("row,why", [
    ('{"file": "a.bvh", "text": "wa\\u0000lks"}', "caption holds the control character"),
    ('{"file": "a\\u0000.bvh", "text": "walks"}', "file name"),
    ('{"file": "a.bvh", "text": "' + "w" * 20_000 + '"}', "over the limit of 10,000"),
])
def test_bad_captions_are_named_by_line(tmp_path, row, why):
    path = tmp_path / "captions.jsonl"
    path.write_text('{"file": "a.bvh", "text": "ok"}\n' + row + "\n")
    with pytest.raises(DatasetError, match=why) as err:
        read_captions(path)
    assert f"{path}:2:" in str(err.value)


def test_an_unterminated_quote_names_its_line(tmp_path):
    path = tmp_path / "captions.csv"
    path.write_text('file,text\na.bvh,walks\nb.bvh,"jumps\nc.bvh,runs\nd.bvh,sits\n')
    with pytest.raises(DatasetError, match="quote") as err:
        read_captions(path)
    assert f"{path}:3:" in str(err.value)
    path.write_text('file,text\na.bvh,"jumps\nc.bvh,runs\nd.bvh,"sits"\n')
    with pytest.raises(DatasetError, match=f"{path}:2:"):
        read_captions(path)


def test_a_2mb_caption_in_csv_is_refused(tmp_path):
    path = tmp_path / "captions.csv"
    path.write_text("file,text\na.bvh," + "w" * 2_000_000 + "\n")
    with pytest.raises(DatasetError, match=f"{path}:2: .*caption has at most"):
        read_captions(path)


def test_a_control_character_in_a_joint_name_is_refused(tmp_path):
    m = _joint_map()
    m["joints"]["root"] = "hi\x00ps"
    path = tmp_path / "m.json"
    path.write_text(json.dumps(m))
    with pytest.raises(MotionlangError, match="control character") as err:
        load_joint_map(path)
    assert str(path) in str(err.value)
    bvh = tmp_path / "x.bvh"
    bvh.write_text("HIERARCHY\nROOT Hi\x01ps\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition "
                   "Yposition Zposition\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\n"
                   "Frames: 1\nFrame Time: 0.1\n0 0 0\n")
    with pytest.raises(MotionlangError, match="control characters") as err:
        read_motion(bvh)
    assert str(bvh) in str(err.value)


def test_a_vocabulary_over_the_limit_is_refused(monkeypatch):
    monkeypatch.setenv("MOTIONLANG_MAX_VOCABULARY", "50")
    with pytest.raises(DatasetError, match="MOTIONLANG_MAX_VOCABULARY"):
        Vocabulary.build([" ".join(f"w{i}x" for i in range(100))])
    assert len(Vocabulary.build(["a person walks"])) == 7


@fifo_only
def test_rig_show_with_a_fifo_joint_map_exits_2_at_once(tmp_path, capsys):
    from motionlang.cli.main import main
    fifo = tmp_path / "map.json"
    os.mkfifo(fifo)
    motion = tmp_path / "x.bvh"
    motion.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition "
                      "Yposition Zposition\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\n"
                      "Frames: 1\nFrame Time: 0.1\n0 0 0\n")
    code = main(["rig", "show", str(motion), "--joint-map", str(fifo)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "FIFO" in err and str(fifo) in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err

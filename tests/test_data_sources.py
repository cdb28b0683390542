"""``--data`` sources as objects: the text they are written as, their kind and loader, the
licence decided from them once."""
from __future__ import annotations

import argparse
import json

import pytest

from helpers.data import bandai_takes
from helpers.kitml import tiny_mmm
from motionlang.datasets import mixing
from motionlang.datasets.sources import (
    KINDS,
    LICENCE_FILE,
    OWN_TERMS,
    DataSource,
    Record,
    SourceKind,
    data_help,
    licence_of,
    licence_text,
    load,
    non_commercial,
    parse_source,
    prefixes,
    register,
)
from motionlang.errors import MotionlangError

BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.033333
0 90 0 0 0 0 0 0 0
0 90 1 0 5 0 0 10 0
0 90 2 0 10 0 0 20 0
"""


@pytest.fixture
def custom(tmp_path):
    root = tmp_path / "mine"
    (root / "sub").mkdir(parents=True)
    (root / "walk.bvh").write_text(BVH)
    (root / "sub" / "idle.bvh").write_text(BVH)
    (root / "captions.csv").write_text("file,text\nwalk.bvh,A person walks.\n"
                                       "sub/idle.bvh,A person stands.\n")
    return root


@pytest.fixture
def kitml(tmp_path):
    """Two made-up KIT-ML motions: 0.5 s and 31 s."""
    root = tmp_path / "kit"
    root.mkdir()
    for mid, frames in (("00001", 50), ("00002", 3100)):
        (root / f"{mid}_mmm.xml").write_bytes(tiny_mmm(frames))
        (root / f"{mid}_annotations.json").write_text(json.dumps(["A person walks."]))
        (root / f"{mid}_meta.json").write_text("{}")
    return root


@pytest.mark.parametrize("text, kind, root, weight", [
    ("bandai:/x/y", "bandai", "/x/y", None),
    ("bandai:/x/y@0.5", "bandai", "/x/y", 0.5),
    ("humanml3d:h3d@2", "humanml3d", "h3d", 2.0),
    ("kitml-h3d:rel/dir", "kitml-h3d", "rel/dir", None),
    ("/data/me@home", "custom", "/data/me@home", None),        # not a number: part of the root
    ("/data/me@home@3", "custom", "/data/me@home", 3.0),      # the last '@' only
    ("C:\\data\\kit@1e-1", "custom", "C:\\data\\kit", 0.1),   # a drive letter is no prefix
    ("s3://bucket/set", "custom", "s3://bucket/set", None),
    ("bandai:C:\\data\\bandai", "bandai", "C:\\data\\bandai", None),
    ("bandai:http://host/x@y", "bandai", "http://host/x@y", None),
])
def test_parse_prefixes_weights_and_odd_paths(text, kind, root, weight):
    s = parse_source(text)
    assert (s.kind, s.root, s.weight) == (kind, root, weight)
    assert str(s) == text.replace("@1e-1", "@0.1") and parse_source(str(s)) == s
    assert s.licence == KINDS[kind].licence


def test_weights_print_back_exactly():
    for w in (1, 2.5, 0.1, 1 / 3, 1e20):
        s = DataSource("bandai", "d", w)
        assert parse_source(str(s)) == s
    assert str(DataSource("bandai", "d", 2)) == "bandai:d@2"


@pytest.mark.parametrize("text, match", [
    ("bandai:", "no folder after 'bandai:'"),
    ("bandai:@2", "no folder after 'bandai:'"),
    ("humanml3d:  ", "no folder after 'humanml3d:'"),
    ("@1", "no dataset before the weight"),
    ("", "no dataset named"), (" ", "no dataset named"),
    ("a@0", "positive number"), ("a@-1", "positive number"), ("a@nan", "positive number"),
    ("a@inf", "positive number"),
])
def test_parse_refuses_in_one_line(text, match):
    with pytest.raises(MotionlangError, match=match) as err:
        parse_source(text)
    assert "\n" not in str(err.value)


def test_bare_folder_kind_by_looking(kitml, custom, tmp_path):
    assert parse_source(str(kitml)).kind == "kitml"
    assert parse_source(str(custom)).kind == "custom"
    assert parse_source(str(tmp_path / "absent")).kind == "custom"   # its loader says so
    assert parse_source(str(kitml), kind="bandai") == DataSource("bandai", str(kitml))
    with pytest.raises(MotionlangError, match="a humanml3d source; expected bandai:DIR"):
        parse_source("humanml3d:x", kind="bandai")
    with pytest.raises(MotionlangError, match="a custom source; expected a bandai one"):
        parse_source(DataSource("custom", "x"), kind="bandai")
    with pytest.raises(MotionlangError, match="unknown data source kind 'bandi'"):
        parse_source("x", kind="bandi")


def test_data_source_checks_its_fields():
    with pytest.raises(MotionlangError, match="unknown data source kind 'kit'"):
        DataSource("kit", "x")
    with pytest.raises(MotionlangError, match="no folder"):
        DataSource("bandai", "")
    with pytest.raises(MotionlangError, match="positive number"):
        DataSource("custom", "x", 0)
    assert DataSource("custom", "x", 3).weight == 3.0
    assert DataSource("bandai", "x").path == "bandai:x"


def test_mixing_keeps_the_names():
    assert mixing.DataSource is DataSource and mixing.parse_source is parse_source


def test_licence_decided_from_the_sources():
    mine, bandai = DataSource("custom", "mine"), DataSource("bandai", "b", 1)
    assert licence_of([mine]) == OWN_TERMS and not non_commercial([mine])
    assert licence_of([mine, bandai]) == "CC BY-NC 4.0" and non_commercial([mine, bandai])
    assert non_commercial("bandai:/x") and not non_commercial("humanml3d:/x")
    assert non_commercial(["corpus", "bandai:/x@2"])
    declared = DataSource("custom", "mine", licence="CC BY-NC 4.0")   # a user's own terms
    assert non_commercial([declared]) and licence_of([declared, bandai]) == "CC BY-NC 4.0"
    assert licence_of([DataSource("custom", "m", licence="CC BY 4.0"), bandai]) == (
        "CC BY 4.0; CC BY-NC 4.0")


def test_licence_text():
    assert licence_text(["corpus", "humanml3d:x"], "M2L") is None
    # the note training runs have written so far, word for word
    assert licence_text(["corpus", "bandai:a", "bandai:b@2"], "M2L") == (
        "Trained on the Bandai Namco Research Motion Datasets (CC BY-NC 4.0): the M2L and the "
        "figures made with it are for non-commercial use only.\n\nData: Bandai Namco Research "
        "Motion Dataset, CC BY-NC 4.0: non-commercial use only, with attribution to Bandai "
        "Namco Research Inc.\nLicence text: https://creativecommons.org/licenses/by-nc/4.0/\n")
    two = licence_text(["bandai:a", DataSource("custom", "m", licence="CC BY-NC 4.0")], "judge")
    assert two.count("Trained on") == 2 and "Trained on custom data (CC BY-NC 4.0)" in two
    assert LICENCE_FILE == "LICENSE.txt"


def test_help_names_every_prefix_and_licence():
    text = data_help()
    for prefix, kind in prefixes().items():
        assert f"{prefix}DIR: {kind.description}" in text
    assert {"bandai:", "humanml3d:", "kitml-h3d:"} <= set(prefixes())
    assert "CC BY-NC 4.0" in text and "@WEIGHT" in text and "@WEIGHT" not in data_help(False)
    assert all(k.description in text for k in KINDS.values())
    # argparse takes it as is (no stray '%')
    p = argparse.ArgumentParser()
    p.add_argument("--data", help=data_help())
    assert "kitml-h3d:DIR" in p.format_help()


def test_register_refuses_a_taken_name_or_prefix():
    with pytest.raises(MotionlangError, match="already registered"):
        register(SourceKind("bandai", "b2:", "m:f", OWN_TERMS, "x"))
    with pytest.raises(MotionlangError, match="prefix 'bandai:'"):
        register(SourceKind("b2", "bandai:", "m:f", OWN_TERMS, "x"))
    assert "b2" not in KINDS


def test_load_a_custom_and_a_kitml_folder(custom, kitml):
    recs = load(str(custom))
    assert [r.id for r in recs] == ["sub/idle", "walk"]
    assert all(isinstance(r, Record) for r in recs)
    assert recs[1].annotations == ["A person walks."] and recs[1].has_annotations
    assert recs[1].load_motion().n_frames == 3
    assert load(DataSource("custom", str(custom), 2.0)) == recs   # the weight is not read
    assert [r.id for r in load(str(kitml))] == ["00001"]            # 31 s left out
    assert [r.id for r in load(str(kitml), max_seconds=None)] == ["00001", "00002"]
    assert all(isinstance(r, Record) for r in load(str(kitml)))


def test_load_records_takes_text_and_sources(custom):
    from motionlang.datasets.seq2seq_pairs import load_records, load_sources
    assert [r.id for r in load_records(str(custom))] == ["sub/idle", "walk"]
    assert [r.id for r in load_records(parse_source(str(custom)))] == ["sub/idle", "walk"]
    records, splits, source_of = load_sources(parse_source(str(custom)))
    assert len(records) == 2 and set(source_of.values()) == {0}


def test_load_a_bandai_source(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    src = bandai_takes(["walk-back_normal_001", "bow_old_001"], tmp_path)
    data = tmp_path / "bandai" / "Bandai-Namco-Research-Motiondataset-1"
    (data / "data").mkdir(parents=True)
    (data / "cfg").mkdir()
    (data / "cfg" / "content_label.txt").write_text("dataset-1_walk-back\ndataset-1_bow\n")
    (data / "cfg" / "style_label.txt").write_text("dataset-1_normal\ndataset-1_old\n")
    for take in ("walk-back_normal_001", "bow_old_001"):
        (data / "data" / f"dataset-1_{take}.bvh").write_bytes((src / f"{take}.bvh").read_bytes())
    source = parse_source(f"bandai:{tmp_path / 'bandai'}@2")
    recs = load(source)
    assert sorted(r.id for r in recs) == ["dataset-1_bow_old_001", "dataset-1_walk-back_normal_001"]
    assert all(isinstance(r, Record) and len(r.annotations) == 3 for r in recs)
    assert {r.split for r in recs} == {"train"}
    assert non_commercial([source]) and licence_of([source]) == "CC BY-NC 4.0"
    assert recs[0].load_motion().meta["licence"] == KINDS["bandai"].notice

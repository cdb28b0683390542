"""KIT-ML end to end: local server -> download -> extract -> load -> filter; splits; TMR."""
from __future__ import annotations

import hashlib

import pytest

from helpers.data import shared_file
from helpers.http_server import serve
from helpers.kitml import build_release, tiny_mmm
from motionlang.datasets.kitml import (
    download_kitml,
    load_annotations_tmr,
    load_kitml,
    load_split,
    load_splits,
    random_split,
)
from motionlang.errors import DatasetError


@pytest.fixture(scope="module")
def release() -> bytes:
    return build_release(shared_file("kitml/00001_mmm.xml").read_bytes())


def test_download_extract_load_filter(tmp_path, release):
    with serve(release, mode="cut") as srv:
        with pytest.raises(DatasetError, match="resum"):
            download_kitml(tmp_path, url=srv.url)
        srv.mode = "ok"
        root = download_kitml(tmp_path, url=srv.url, sha256=hashlib.sha256(release).hexdigest())
        assert srv.requests[-1][1] is not None          # the second attempt resumed
    assert (tmp_path / "data.zip").read_bytes() == release
    assert not list(root.rglob("*.c3d"))                 # raw markers not extracted
    recs = load_kitml(tmp_path)                          # finds the top-level folder itself
    assert [r.id for r in recs] == ["00001", "00007"]    # 31 s motion dropped
    r1, r7 = recs
    assert r1.n_frames == 378 and r1.duration_s == pytest.approx(3.78)
    assert r1.annotations == ["A person walks forward.", "Someone takes a few steps."]
    assert r1.meta["source"]["database"]["identifier"] == "kit"
    assert r7.annotations == [] and not r7.has_annotations and r1.has_annotations
    everything = load_kitml(root, max_seconds=None)
    assert [r.id for r in everything] == ["00001", "00002", "00007"]
    assert everything[1].duration_s == pytest.approx(31.0)
    assert [r.id for r in load_kitml(root, max_seconds=3.78)] == ["00007"]  # ">= max" dropped
    pytest.importorskip("motionlang.formats.mmm")
    motion = r1.load_motion()
    assert motion.joint_angles.shape[0] == 378 and motion.fps == pytest.approx(100.0)


def test_download_checksum_mismatch_leaves_nothing(tmp_path, release):
    with serve(release) as srv:
        with pytest.raises(DatasetError, match="sha256"):
            download_kitml(tmp_path, url=srv.url, sha256="ab" * 32)
    assert not (tmp_path / "kitml").exists() and not list(tmp_path.glob("*.zip*"))


def test_malformed_annotations_name_file_and_line(tmp_path):
    (tmp_path / "00005_mmm.xml").write_bytes(tiny_mmm(10))
    (tmp_path / "00005_meta.json").write_text("{}")
    (tmp_path / "00005_annotations.json").write_text('[\n"ok",\n oops]')
    with pytest.raises(DatasetError, match=r"00005_annotations.json:3"):
        load_kitml(tmp_path)
    (tmp_path / "00005_annotations.json").write_text('{"a": 1}')
    with pytest.raises(DatasetError, match="list of strings"):
        load_kitml(tmp_path)
    (tmp_path / "00005_annotations.json").write_text("[]")
    assert not load_kitml(tmp_path)[0].has_annotations  # kept by default, as in the release
    with pytest.raises(DatasetError, match=r"00005_annotations.json: empty annotation list"):
        load_kitml(tmp_path, require_annotations=True)
    (tmp_path / "00005_meta.json").unlink()
    with pytest.raises(DatasetError, match="00005_meta.json: missing"):
        load_kitml(tmp_path)
    with pytest.raises(DatasetError, match="not found"):
        load_kitml(tmp_path / "nowhere")


def test_published_splits_load_with_readme_sizes():
    temos = load_splits(shared_file("kitml/splits_temos"))
    assert {k: len(v) for k, v in temos.items()} == \
        {"train": 1784, "val": 566, "test": 587, "ghosh_test": 520}
    assert not set(temos["train"]) & set(temos["test"])
    tmr = load_splits(shared_file("kitml/splits_tmr"))
    parts = [set(tmr[k]) for k in ("train", "val", "test")]
    assert set().union(*parts) == set(tmr["all"]) and sum(map(len, parts)) == len(tmr["all"])
    assert any(i.startswith("M") for i in tmr["train"]) and "00001" in tmr["all"]


def test_load_split_errors(tmp_path):
    p = tmp_path / "s.txt"
    p.write_text("00001\n\n00002 00003\n")
    with pytest.raises(DatasetError, match="s.txt:3"):
        load_split(p)
    with pytest.raises(DatasetError):
        load_split(tmp_path / "missing.txt")


def test_random_split():
    ids = [f"{i:05d}" for i in range(1, 101)] + [f"M{i:05d}" for i in range(1, 101)]
    s = random_split(ids, (0.8, 0.1, 0.1), seed=0)
    assert [len(s[k]) for k in ("train", "val", "test")] == [160, 20, 20]
    assert sorted(s["train"] + s["val"] + s["test"]) == sorted(ids)
    for part in s.values():                              # mirrored copies stay together
        assert {i.lstrip("M") for i in part if i.startswith("M")} == \
            {i for i in part if not i.startswith("M")}
    assert s == random_split(list(reversed(ids)), (0.8, 0.1, 0.1), seed=0)
    assert s != random_split(ids, (0.8, 0.1, 0.1), seed=1)
    s2 = random_split(ids[:100], (0.6, 0.2, 0.2), seed=3)
    assert [len(s2[k]) for k in ("train", "val", "test")] == [60, 20, 20]
    assert set(random_split(ids, (0.5, 0.5))) == {"train", "test"}
    with pytest.raises(DatasetError, match="fractions"):
        random_split(ids, (0.8, 0.3, 0.1))


def test_annotations_tmr():
    tmr = load_annotations_tmr(shared_file("kitml/annotations_tmr.json"))
    originals = [k for k in tmr if not k.startswith("M")]
    assert len(originals) == 2883 and len(tmr) == 2 * 2883
    assert sum(len(tmr[k]["texts"]) for k in originals) == 6082
    assert tmr["00001"]["texts"] == ["A person is walking forwards."]
    assert tmr["00001"]["duration"] == pytest.approx(3.78)


def test_cheap_frame_count_matches_exact_count(tmp_path):
    from motionlang.datasets.kitml import count_mmm_frames
    real = shared_file("kitml/00001_mmm.xml")
    assert count_mmm_frames(real) == count_mmm_frames(real, window=1 << 30) == 378
    p = tmp_path / "t_mmm.xml"
    p.write_bytes(tiny_mmm(3100))
    assert p.stat().st_size > 2 * (1 << 16)          # large enough for the cheap path
    assert count_mmm_frames(p) == count_mmm_frames(p, window=1 << 30) == 3100

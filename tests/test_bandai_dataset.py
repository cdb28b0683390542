"""The Bandai Namco dataset: finding takes in archives, clones and folders; labels; splits."""
from __future__ import annotations

import io
import os
import tarfile
from pathlib import Path

import pytest

from helpers.data import shared_file
from motionlang.datasets.bandai import bandai_folders, load_bandai, split_of
from motionlang.errors import DatasetError

BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 90 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  End Site
  {
    OFFSET 0 10 0
  }
}
MOTION
Frames: 2
Frame Time: 0.0333333
0 90 0 0 0 0
0 90 1 0 0 0
"""


def _archive(path: Path, n: int, takes: list[str], extra: dict | None = None) -> Path:
    top = f"Bandai-Namco-Research-Motiondataset-{n}"
    files = {f"{top}/cfg/content_label.txt": f"dataset-{n}_walk\ndataset-{n}_walk-turn-left\n",
             f"{top}/cfg/style_label.txt": f"dataset-{n}_normal\ndataset-{n}_elderly\n",
             f"{top}/LICENSE": "CC BY-NC 4.0\n"}
    for t in takes:
        files[f"{top}/data/dataset-{n}_{t}.bvh"] = BVH
        files[f"{top}/data/dataset-{n}_{t}.json"] = "{}"
    files.update(extra or {})
    with tarfile.open(path / f"{top}.tar.xz", "w:xz") as tf:
        for name, text in files.items():
            data = text.encode()
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tf.addfile(info, io.BytesIO(data))
    return path / f"{top}.tar.xz"


def test_splits_are_take_numbers_mod_5():
    assert [split_of(2, t) for t in range(1, 11)] == (
        ["train", "train", "train", "val", "test"] * 2)
    assert {split_of(1, t) for t in range(1, 11)} == {"train"}


def test_archives_extracted_once_into_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    src = tmp_path / "src"
    src.mkdir()
    _archive(src, 1, ["walk_normal_001"])
    _archive(src, 2, [f"walk-turn-left_elderly_{t:03d}" for t in range(1, 6)])
    recs = load_bandai(src)
    assert [r.id for r in recs][:2] == ["dataset-1_walk_normal_001",
                                        "dataset-2_walk-turn-left_elderly_001"]
    r = recs[-1]
    assert (r.dataset, r.content, r.style, r.take, r.split) == (2, "walk-turn-left", "elderly",
                                                                5, "test")
    assert tmp_path / "cache" in r.path.parents and src not in r.path.parents
    assert [x.take for x in load_bandai(src, "val")] == [4]
    m = r.load_motion()
    assert m.meta["content"] == "walk-turn-left" and "non-commercial" in m.meta["licence"]
    # a second call reuses the extraction; nothing but the dataset folder in the cache
    before = r.path.stat().st_mtime_ns
    assert load_bandai(src)[-1].path.stat().st_mtime_ns == before
    # ... and so does a copy of the same archive with a new time (a fresh checkout)
    archive = src / "Bandai-Namco-Research-Motiondataset-2.tar.xz"
    os.utime(archive, ns=(archive.stat().st_atime_ns, archive.stat().st_mtime_ns + 10**9))
    assert load_bandai(src)[-1].path.stat().st_mtime_ns == before
    assert sorted(p.name for p in (tmp_path / "cache" / "bandai").iterdir()) == [
        "Bandai-Namco-Research-Motiondataset-1", "Bandai-Namco-Research-Motiondataset-2"]
    # the extracted folder (as in a clone of the repository) reads the same
    clone = r.path.parents[1]
    assert [x.id for x in load_bandai(clone)] == [x.id for x in recs if x.dataset == 2]


def test_bad_sources_are_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    with pytest.raises(DatasetError, match="not found"):
        bandai_folders(tmp_path / "nope")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DatasetError, match="no Bandai Namco dataset"):
        bandai_folders(tmp_path / "empty")
    bad = tmp_path / "bad"
    bad.mkdir()
    _archive(bad, 2, ["walk_angry_001"])
    with pytest.raises(DatasetError, match="'angry' not in the labels"):
        load_bandai(bad)
    evil = tmp_path / "evil"
    evil.mkdir()
    _archive(evil, 1, ["walk_normal_001"], {"../outside/data/x.bvh": BVH})
    with pytest.raises(DatasetError, match="unsafe path"):
        load_bandai(evil)
    # the member would have landed beside the extraction folder, in cache/bandai
    assert not (tmp_path / "cache" / "bandai" / "outside").exists()
    assert not (tmp_path / "cache" / "outside").exists()
    leftovers = [p for p in (tmp_path / "cache" / "bandai").iterdir() if p.name.startswith(".")]
    assert leftovers == []
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "Bandai-Namco-Research-Motiondataset-1.tar.xz").write_bytes(b"<html>oops")
    with pytest.raises(DatasetError, match="not a valid tar archive"):
        load_bandai(broken)


def test_real_dataset_1_archive(tmp_path, monkeypatch):
    archive = shared_file("bandai/Bandai-Namco-Research-Motiondataset-1.tar.xz")
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    src = tmp_path / "src"
    src.mkdir()
    (src / archive.name).symlink_to(archive)
    recs = load_bandai(src)
    assert len(recs) == 174 and {r.split for r in recs} == {"train"}
    # 17 contents are labelled, but the one take of 'dance-long' (normal) is missing
    assert len({r.content for r in recs}) == 16 and len({r.style for r in recs}) == 15
    assert "dance-long" not in {r.content for r in recs}

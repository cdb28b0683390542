"""A file link in a dataset folder that leads out of it is refused by every loader, as a
folder link is (issue 44, item 0); the custom folder's case is in test_custom_dataset."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motionlang.datasets.bandai import load_bandai
from motionlang.datasets.humanml3d import load_h3d
from motionlang.datasets.kitml import load_kitml
from motionlang.errors import DatasetError

REFUSED = "a symbolic link that leads out of the dataset folder"


def link_out(inside: Path, outside: Path, data: bytes = b"x") -> None:
    outside.parent.mkdir(parents=True, exist_ok=True)
    outside.write_bytes(data)
    inside.parent.mkdir(parents=True, exist_ok=True)
    inside.symlink_to(outside)


def test_kitml_folder(tmp_path):
    from motionlang.datasets.synth.corpus import write_corpus
    folder = tmp_path / "kit"
    write_corpus(folder, 2, seed=0, workers=1, show_progress=False)
    assert len(load_kitml(folder)) == 2
    moved = tmp_path / "elsewhere" / "00002_mmm.xml"
    moved.parent.mkdir()
    (folder / "00002_mmm.xml").rename(moved)
    (folder / "00002_mmm.xml").symlink_to(moved)
    with pytest.raises(DatasetError, match=f"00002_mmm.xml: {REFUSED}"):
        load_kitml(folder)
    (folder / "00002_mmm.xml").unlink()
    (folder / "00002_mmm.xml").symlink_to(folder / "00001_mmm.xml")   # inside: fine
    assert len(load_kitml(folder)) == 2


def test_humanml3d_folder(tmp_path):
    root = tmp_path / "h3d"
    buf = tmp_path / "rows.npy"
    np.save(buf, np.zeros((3, 251), dtype=np.float32))
    link_out(root / "new_joint_vecs" / "1.npy", tmp_path / "out" / "1.npy", buf.read_bytes())
    with pytest.raises(DatasetError, match=f"1.npy: {REFUSED}"):
        load_h3d(root, "kit")


def test_bandai_folder(tmp_path):
    folder = tmp_path / "bandai"
    (folder / "cfg").mkdir(parents=True)
    (folder / "cfg" / "content_label.txt").write_text("dataset-2_walk\n")
    (folder / "cfg" / "style_label.txt").write_text("dataset-2_normal\n")
    link_out(folder / "data" / "dataset-2_walk_normal_001.bvh", tmp_path / "x.bvh")
    with pytest.raises(DatasetError, match=f"dataset-2_walk_normal_001.bvh: {REFUSED}"):
        load_bandai(folder)

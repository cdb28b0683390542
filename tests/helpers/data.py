"""Where the real data lives (``../shared/data`` beside the project), and files from it;
tests that need a file skip cleanly where it is absent."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data"


def shared_file(rel: str) -> Path:
    """``../shared/data/<rel>``; skips the test where that file is absent."""
    path = SHARED / rel
    if not path.exists():
        pytest.skip(f"real data file {path} not present")
    return path


def bandai_takes(takes: list[str] | tuple[str, ...], dest: Path) -> Path:
    """Dataset-1 Bandai Namco takes (``"walk_normal_001"``...) extracted from the archive in
    the shared data into ``dest`` as ``<take>.bvh`` (never from a copy in the repo); skips
    where the archive is absent."""
    import tarfile

    archive = shared_file("bandai/Bandai-Namco-Research-Motiondataset-1.tar.xz")
    want = {f"Bandai-Namco-Research-Motiondataset-1/data/dataset-1_{t}.bvh": t for t in takes}
    with tarfile.open(archive, "r:xz") as tar:
        for member in tar:
            if member.name in want:
                (dest / f"{want.pop(member.name)}.bvh").write_bytes(
                    tar.extractfile(member).read())
                if not want:
                    break
    assert not want, f"missing from the archive: {sorted(want)}"
    return dest


#: the takes of dataset 1 that :func:`bandai_folder` lays out as dataset 2's
BANDAI_TAKES = ("walk_normal_001", "walk-back_normal_001", "bye_happy_001")


def bandai_folder(tmp: Path) -> Path:
    """A small Bandai dataset-2 folder under ``tmp``: contents walk / wave-left-hand,
    styles normal / elderly, takes 1..5 of each pair (take 5: test, 4: validation), each a
    real dataset-1 take (:func:`bandai_takes`); skips where the archive is absent."""
    tmp.mkdir(parents=True, exist_ok=True)
    src = bandai_takes(BANDAI_TAKES, tmp)
    top = tmp / "bandai" / "Bandai-Namco-Research-Motiondataset-2"
    (top / "data").mkdir(parents=True)
    (top / "cfg").mkdir()
    (top / "cfg" / "content_label.txt").write_text("dataset-2_walk\ndataset-2_wave-left-hand\n")
    (top / "cfg" / "style_label.txt").write_text("dataset-2_normal\ndataset-2_elderly\n")
    for k, (content, style) in enumerate([("walk", "normal"), ("walk", "elderly"),
                                          ("wave-left-hand", "normal"),
                                          ("wave-left-hand", "elderly")]):
        for t in range(1, 6):
            take = BANDAI_TAKES[(k + t) % len(BANDAI_TAKES)]
            (top / "data" / f"dataset-2_{content}_{style}_{t:03d}.bvh").write_bytes(
                (src / f"{take}.bvh").read_bytes())
    return tmp / "bandai"

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

"""Shared fixtures: where the real data lives, and a tiny hand-made skeleton."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motionlang.kinematics import Joint, Motion, Skeleton

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ../shared/data; tests that use it skip cleanly where it is absent."""
    if not SHARED.is_dir():
        pytest.skip(f"real data folder {SHARED} not present")
    return SHARED


def shared_file(rel: str) -> Path:
    path = SHARED / rel
    if not path.exists():
        pytest.skip(f"real data file {path} not present")
    return path


def tiny_skeleton() -> Skeleton:
    """Hips with two 2-link legs (1 m thigh along -y, knee about x) and a spine."""
    S = np.diag([-1.0, 1.0, 1.0])
    x, y, z = np.eye(3)
    joints = [
        Joint("Hips", -1, [0, 0, 0]),
        Joint("LeftUpLeg", 0, [0.1, 0, 0], axes=[z, x, y]),
        Joint("LeftLeg", 1, [0, -1.0, 0], axes=[x]),
        Joint("LeftFoot", 2, [0, -1.0, 0]),
        Joint("RightUpLeg", 0, [-0.1, 0, 0], axes=[z, x, y]),
        Joint("RightLeg", 4, [0, -1.0, 0], axes=[x]),
        Joint("RightFoot", 5, [0, -1.0, 0]),
        Joint("Spine", 0, [0, 0.5, 0], axes=[z, x, y]),
    ]
    return Skeleton(joints, name="tiny", mirror=S)


@pytest.fixture
def tiny_motion() -> Motion:
    rng = np.random.default_rng(0)
    sk = tiny_skeleton()
    T = 20
    return Motion(sk, 30.0, rng.normal(size=(T, 3)), rng.uniform(-1, 1, (T, 3)),
                  rng.uniform(-1, 1, (T, sk.ndof)), name="tiny")


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

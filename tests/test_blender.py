"""Blender, headless, imports the BVH and the GLB motionlang writes and puts every joint
where motionlang's forward kinematics does (``benchmarks/blender_check.py``); skipped where
``blender`` is not on PATH (``apt-get install -y blender python3-numpy``)."""
from __future__ import annotations

import shutil

import pytest

from helpers.data import SHARED
from helpers.rigs import RIGS, write
from helpers.scripts import ROOT, load_script
from motionlang.features.joint_map import positions21
from motionlang.formats import read_motion
from motionlang.rendering.output import body_motion

BLENDER = shutil.which("blender")
pytestmark = pytest.mark.skipif(BLENDER is None, reason="blender is not on PATH")


def test_blender_reads_our_bvh_and_glb_within_a_millimetre(tmp_path):
    check = load_script(ROOT / "benchmarks" / "blender_check.py")
    bandai = read_motion(write(RIGS["bandai"], tmp_path, T=8))
    motions = {"body21": body_motion(positions21(bandai), bandai.fps, name="body21")[0],
               "bandai": bandai,
               "cmu_bvh": read_motion(write(RIGS["cmu-bvh"], tmp_path, T=8))}
    amc = SHARED / "cmu35" / "35_01.amc"
    if amc.is_file():   # the real ASF/AMC rig (hinged joints, ASF axes) where present
        motions["cmu_asf"] = read_motion(amc)[:8]
    work = tmp_path / "out"
    work.mkdir()
    rows = check.check(motions, work, BLENDER)
    assert len(rows) == 2 * len(motions)
    for row in rows:
        assert row["ok"], check.table([row])
        assert row["frames"] == 8 and row["max_mm"] < 0.05 and not row["missing"]

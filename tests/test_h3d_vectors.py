"""HumanML3D vectors: the layout, rows worked out by hand, and joints -> rows -> joints on
real motions."""
from __future__ import annotations

import numpy as np
import pytest

from helpers.data import shared_file
from motionlang.errors import MotionlangError
from motionlang.features.base import downsample
from motionlang.features.h3d_vectors import (
    HEADINGS,
    KIT_H3D,
    SMPL_H3D,
    group_std,
    heading_yaw,
    joints_to_vectors,
    mirror_joints,
    rotation_channels,
    vector_dim,
    vector_slices,
    vectors_to_joints,
)
from motionlang.features.joint_map import KIT21_PARENTS, positions21
from motionlang.features.root import rot_y
from motionlang.formats import read_motion

# A KIT body standing at attention, in millimetres, facing +Z, every bone along its
# raw_offsets direction (so every rotation channel is the identity).
STAND = np.array([
    [0, 900, 0], [0, 1000, 0], [0, 1100, 0], [0, 1400, 0], [0, 1500, 0],    # root..BUN
    [200, 1400, 0], [200, 1100, 0], [200, 850, 0],                            # LS LE LW
    [-200, 1400, 0], [-200, 1100, 0], [-200, 850, 0],                         # RS RE RW
    [100, 900, 0], [100, 500, 0], [100, 100, 0], [100, 100, 60], [100, 100, 160],
    [-100, 900, 0], [-100, 500, 0], [-100, 100, 0], [-100, 100, 60], [-100, 100, 160]],
    dtype=float)
IDENTITY_6D = [1, 0, 0, 0, 1, 0]


def _parts(row: np.ndarray, J: int) -> dict[str, np.ndarray]:
    return {k: row[s] for k, s in vector_slices(J).items()}


def test_layout_sizes_and_bodies():
    assert vector_dim(22) == 263 == SMPL_H3D.dim and vector_dim(21) == 251 == KIT_H3D.dim
    sl = vector_slices(22)
    assert [sl[k].stop - sl[k].start for k in sl] == [1, 2, 1, 63, 126, 66, 4]
    assert sl["contacts"].stop == 263
    assert SMPL_H3D.parents == (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16,
                                17, 18, 19)
    assert KIT_H3D.parents == KIT21_PARENTS
    assert SMPL_H3D.mirror[1:3] == (2, 1) and SMPL_H3D.mirror[15] == 15


def test_two_frames_by_hand_walking_step():
    """Frame 1: everything 100 mm right-ward (x) and 200 mm forward, but the left foot."""
    f1 = STAND + [100, 0, 200]
    f1[[13, 14, 15]] = STAND[[13, 14, 15]]
    rows, layout = joints_to_vectors(np.stack([STAND, f1]), KIT_H3D)
    assert rows.shape == (1, 251)
    got = _parts(rows[0], 21)
    assert got["root_yaw_velocity"] == pytest.approx([0.0], abs=1e-12)
    assert got["root_velocity_xz"] == pytest.approx([100, 200])
    assert got["root_height"] == pytest.approx([800])           # floor: the ankles at 100
    assert got["ric"] == pytest.approx((STAND[1:] - [0, 100, 0]).ravel())
    assert got["rotations"] == pytest.approx(IDENTITY_6D * 20, abs=1e-12)
    vel = np.tile([100.0, 0, 200], (21, 1))
    vel[[13, 14, 15]] = 0
    assert got["velocities"] == pytest.approx(vel.ravel())
    # contacts: left mid-foot and toe stayed (0 < 0.05 mm^2), the right ones moved
    assert list(got["contacts"]) == [1, 1, 0, 0]
    assert layout[0] == pytest.approx(STAND - [0, 100, 0])


def test_two_frames_by_hand_quarter_turn():
    """Frame 1: the body turned 90 degrees to its left (now facing +X), 100 mm along +X."""
    rel = STAND - STAND[0]
    f1 = np.stack([rel[:, 2], rel[:, 1], -rel[:, 0]], axis=1) + STAND[0] + [100, 0, 0]
    rows, _ = joints_to_vectors(np.stack([STAND, f1]), KIT_H3D, heading="body")
    got = _parts(rows[0], 21)
    assert got["root_yaw_velocity"] == pytest.approx([-np.pi / 4])   # -(pi/2) / 2
    assert got["root_velocity_xz"] == pytest.approx([0, 100])        # straight ahead
    assert got["root_height"] == pytest.approx([800])
    assert got["rotations"] == pytest.approx(IDENTITY_6D * 20, abs=1e-12)
    assert got["velocities"] == pytest.approx((f1 - STAND).ravel())  # frame 0 faces +Z
    assert list(got["contacts"]) == [0, 0, 0, 0]
    assert vectors_to_joints(rows, KIT_H3D)[0] == pytest.approx(STAND - [0, 100, 0])


def _kit_mm(rel: str, fps: float = 12.5) -> np.ndarray:
    return positions21(downsample(read_motion(shared_file(rel)), fps)) * 1000.0


@pytest.mark.parametrize("rel", ["kitml/00001_mmm.xml", "cmu35/35_01.amc"])
@pytest.mark.parametrize("heading", HEADINGS)
def test_joints_rows_joints_real_motions(rel, heading):
    p = _kit_mm(rel)
    rows, layout = joints_to_vectors(p, KIT_H3D, heading)
    assert rows.shape == (len(p) - 1, 251)
    back = vectors_to_joints(rows.astype(np.float32), KIT_H3D)     # as written to a file
    assert np.abs(back - layout[:-1]).max() * KIT_H3D.unit < 1e-4  # metres
    # the layout joints are the input moved rigidly: same distances, heights shifted
    def dists(x):
        return np.linalg.norm(x[:, :, None] - x[:, None], axis=-1)
    assert np.abs(dists(layout) - dists(p)).max() < 1e-6
    dy = layout[..., 1] - p[..., 1]
    assert np.ptp(dy) < 1e-6 and layout[..., 1].min() == pytest.approx(0, abs=1e-9)
    assert layout[0, 0, [0, 2]] == pytest.approx([0, 0], abs=1e-9)
    assert heading_yaw(layout, KIT_H3D, heading)[0] == pytest.approx(0, abs=1e-9)


def test_smpl_body_round_trip():
    """22 joints (an SMPL-like body made from the CMU motion's 21) at 20 fps, metres."""
    p21 = _kit_mm("cmu35/35_01.amc", 20.0) / 1000.0
    idx = [0, 11, 16, 1, 12, 17, 2, 13, 18, 3, 14, 19, 3, 3, 3, 4, 5, 8, 6, 9, 7, 10]
    p = p21[:, idx] + np.array([0, 0.05, 0]) * (np.arange(22) == 12)[:, None]
    p[:, [13, 14]] = (p21[:, [5, 8]] + p21[:, [3]]) / 2          # collars between
    rows, layout = joints_to_vectors(p, SMPL_H3D)
    assert rows.shape == (len(p) - 1, 263)
    assert np.abs(vectors_to_joints(rows.astype(np.float32), SMPL_H3D) - layout[:-1]).max() \
        < 1e-4


@pytest.mark.parametrize("source", ["kitml/00001_mmm.xml", "arms up"])
def test_rotation_channels_rebuild_the_bones(source):
    """The public FK (chain products from Ry(-yaw), times raw_offsets) points every bone
    where the joints do, also a bone opposite its rest direction (forearms raised)."""
    if source == "arms up":
        up = STAND.copy()
        up[[6, 7, 9, 10]] = up[[5, 5, 8, 8]] + [[0, 300, 0], [0, 550, 0]] * 2
        p = np.stack([up, up + [0, 0, 50]])
    else:
        p = _kit_mm(source)
    yaw = heading_yaw(p, KIT_H3D)
    six = rotation_channels(p, yaw, KIT_H3D).reshape(len(p), 20, 2, 3)
    c0, c1 = six[:, :, 0], six[:, :, 1]
    local = np.stack([c0, c1, np.cross(c0, c1)], axis=-1)          # (T, 20, 3, 3) columns
    for chain in KIT_H3D.chains:
        R = rot_y(-yaw)
        for a, b in zip(chain[:-1], chain[1:]):
            R = R @ local[:, b - 1]
            bone = p[:, b] - p[:, a]
            got = R @ np.array(KIT_H3D.raw_offsets[b], dtype=float)
            assert got == pytest.approx(bone / np.linalg.norm(bone, axis=1, keepdims=True),
                                        abs=1e-9)


def _spin(turns: float, T: int) -> np.ndarray:
    """STAND turning in place about its root by ``turns`` full turns over T frames."""
    yaw = np.linspace(0.0, 2 * np.pi * turns, T)
    rel = STAND - STAND[0]
    return np.einsum("tij,kj->tki", rot_y(yaw), rel) + STAND[0]


def test_yaw_velocity_is_exact_across_180_degrees():
    p = _spin(1.25, 41)                      # crosses +-180 degrees at frame 16
    rows, layout = joints_to_vectors(p, KIT_H3D, "body")
    step = 2 * np.pi * 1.25 / 40
    assert rows[:, 0] == pytest.approx(np.full(40, -step / 2))
    assert np.abs(vectors_to_joints(rows, KIT_H3D) - layout[:-1]).max() < 1e-9


def test_mirrored_copy_is_the_mirror_image():
    p = _kit_mm("kitml/00001_mmm.xml")
    assert mirror_joints(mirror_joints(p, KIT_H3D), KIT_H3D) == pytest.approx(p)
    m = mirror_joints(p, KIT_H3D)
    assert m[:, 11] == pytest.approx(p[:, 16] * [-1, 1, 1])       # LH <- mirrored RH
    for heading in HEADINGS:
        rows, _ = joints_to_vectors(p, KIT_H3D, heading)
        mrows, _ = joints_to_vectors(m, KIT_H3D, heading)
        assert mrows[:, 0] == pytest.approx(-rows[:, 0])           # turns the other way
        back, mback = vectors_to_joints(rows, KIT_H3D), vectors_to_joints(mrows, KIT_H3D)
        assert mback == pytest.approx(mirror_joints(back, KIT_H3D), abs=1e-6)
        assert list(mrows[:, -4:].sum(0)) == list(rows[:, [-2, -1, -4, -3]].sum(0))


def test_group_std_and_errors():
    std = np.arange(251, dtype=float)
    std[vector_slices(21)["contacts"]] = 0
    g = group_std(std, 21)
    sl = vector_slices(21)
    assert g[sl["ric"]] == pytest.approx(np.full(60, np.arange(4, 64).mean()))
    assert g[sl["root_velocity_xz"]] == pytest.approx([1.5, 1.5])
    assert list(g[sl["contacts"]]) == [1, 1, 1, 1]
    with pytest.raises(MotionlangError, match="T >= 2"):
        joints_to_vectors(STAND[None], KIT_H3D)
    with pytest.raises(MotionlangError, match=r"\(N >= 1, 263\)"):
        vectors_to_joints(np.zeros((3, 251)), SMPL_H3D)
    with pytest.raises(MotionlangError, match="heading"):
        heading_yaw(np.stack([STAND, STAND]), KIT_H3D, "smoothed")

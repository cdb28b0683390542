"""DeepMimic clips (``formats.deepmimic``): the frame layout worked out by hand (the rest
pose is the humanoid's URDF offsets, a knee angle bends the knee, every quaternion comes back
as the joint's rotation), frame rates and re-timing, the 21-joint body, the folder scan, one
clear line for every malformed file; and the clips of the pybullet wheel where present
(``MOTIONLANG_DEEPMIMIC``, else ``../extern/pybullet_data/data/motions`` beside the project)."""
from __future__ import annotations

import json
import os
import random
from pathlib import Path

import numpy as np
import pytest

from helpers.data import ROOT
from motionlang.cli.main import main
from motionlang.errors import MotionFormatError
from motionlang.features.body21 import body21
from motionlang.features.joint_map import KIT21_NAMES, match_rig, positions21
from motionlang.formats import is_motion_file, read_motion, write_motion
from motionlang.formats.deepmimic import frame_rate, motion_from_frames, read_deepmimic
from motionlang.kinematics.rotations import chain
from motionlang.library.scan import motion_files

I = {n: i for i, n in enumerate(KIT21_NAMES)}
#: columns of each moving joint in a frame, written out from the format's description
QUATS = {"root": 4, "chest": 8, "neck": 12, "right_hip": 16, "right_ankle": 21,
         "right_shoulder": 25, "left_hip": 30, "left_ankle": 35, "left_shoulder": 39}
ANGLES = {"right_knee": 20, "right_elbow": 29, "left_knee": 34, "left_elbow": 43}
#: humanoid.urdf (x 0.25): hip to knee 0.421546, knee to ankle 0.40987, ankle to sole 0.05
SOLE_BELOW_ROOT = 0.421546 + 0.40987 + 0.05
REAL = Path(os.environ.get("MOTIONLANG_DEEPMIMIC")
            or ROOT.parent / "extern" / "pybullet_data" / "data" / "motions")


def still(n=1, dt=1 / 30, height=SOLE_BELOW_ROOT) -> np.ndarray:
    """(n, 44) frames of the rest pose, root ``height`` above the origin."""
    f = np.zeros((n, 44))
    f[:, 0] = dt
    f[-1, 0] = 0.0
    f[:, 2] = height
    for c in QUATS.values():
        f[:, c] = 1.0
    return f


def quat(axis, angle) -> np.ndarray:
    """(w, x, y, z) of a turn by ``angle`` about the unit ``axis``."""
    return np.r_[np.cos(angle / 2), np.sin(angle / 2) * np.asarray(axis, dtype=float)]


def qmat(q) -> np.ndarray:
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def write_clip(path: Path, frames, loop="wrap") -> Path:
    path.write_text(json.dumps({"Loop": loop, "Frames": np.asarray(frames).tolist()}))
    return path


def walk(n=40, fps=30.0) -> np.ndarray:
    """A crude walk along +x at 1 m/s: hips swinging, knees bending, arms counter-swinging."""
    f = still(n, 1 / fps, SOLE_BELOW_ROOT - 0.02)
    t = np.arange(n) / fps
    f[:, 1] = t
    swing = 0.4 * np.sin(2 * np.pi * t)
    for side, s in (("right", 1.0), ("left", -1.0)):
        f[:, QUATS[f"{side}_hip"]:QUATS[f"{side}_hip"] + 4] = [quat([0, 0, 1], s * a)
                                                               for a in swing]
        f[:, ANGLES[f"{side}_knee"]] = -0.3 - 0.3 * np.maximum(0, s * swing)
        f[:, QUATS[f"{side}_shoulder"]:QUATS[f"{side}_shoulder"] + 4] = [
            quat([0, 0, 1], -s * 0.5 * a) for a in swing]
        f[:, ANGLES[f"{side}_elbow"]] = 0.3
    return f


def pos(m, name) -> np.ndarray:
    return m.positions()[:, m.skeleton.index(name)]


# ----------------------------------------------------------------------- the frame layout
def test_rest_pose_is_the_urdf_body_standing_on_its_soles(tmp_path):
    m = read_motion(write_clip(tmp_path / "rest.txt", still(3)))
    assert m.source_format == "deepmimic" and m.n_frames == 3 and m.fps == 30.0
    assert m.skeleton.ndof == 28 and m.meta["loop"] == "wrap" and not m.meta["retimed"]
    root = np.array([0.0, SOLE_BELOW_ROOT, 0.0])
    expect = {"chest": (0, 0.236151, 0), "neck": (0, 0.236151 + 0.223894, 0),
              "right_hip": (0, 0, 0.084887), "left_hip": (0, 0, -0.084887),
              "right_knee": (0, -0.421546, 0.084887), "left_ankle": (0, -0.831416, -0.084887),
              "right_foot_tip": (0.1335, -0.881416, 0.084887),
              "right_shoulder": (-0.02405, 0.236151 + 0.2435, 0.18311),
              "left_wrist": (-0.02405, 0.236151 + 0.2435 - 0.274788 - 0.258947, -0.18311),
              "head_top": (0, 0.236151 + 0.223894 + 0.2775, 0)}
    for name, offset in expect.items():
        assert np.allclose(pos(m, name), root + offset, atol=1e-6), name
    p = m.positions()[0]
    assert abs(p[:, 1].min()) < 1e-9                    # the soles on the floor
    assert 1.60 < p[:, 1].max() < 1.64                   # a 1.6 m body


def test_knee_elbow_and_hip_angles_bend_the_way_the_urdf_says(tmp_path):
    f = still()
    f[0, ANGLES["right_knee"]] = -np.pi / 2              # knees bend at negative angles
    f[0, ANGLES["left_elbow"]] = np.pi / 2               # elbows at positive ones
    f[0, QUATS["left_hip"]:QUATS["left_hip"] + 4] = quat([0, 0, 1], np.pi / 6)
    m = read_motion(write_clip(tmp_path / "bent.txt", f))
    shin = pos(m, "right_ankle") - pos(m, "right_knee")
    assert np.allclose(shin, [[-0.40987, 0, 0]], atol=1e-6)           # the shin points back
    forearm = pos(m, "left_wrist") - pos(m, "left_elbow")
    assert np.allclose(forearm, [[0.258947, 0, 0]], atol=1e-6)        # the forearm forward
    thigh = pos(m, "left_knee") - pos(m, "left_hip")
    assert np.allclose(thigh, [[0.421546 * np.sin(np.pi / 6), -0.421546 * np.cos(np.pi / 6),
                                0]], atol=1e-6)                          # the thigh raised


def test_every_quaternion_comes_back_as_its_joints_rotation():
    rng = np.random.default_rng(0)
    f = still(5)
    for c in QUATS.values():
        f[:, c:c + 4] = rng.normal(size=(5, 4)) * rng.uniform(0.5, 1.5, size=(5, 1))
    for c in ANGLES.values():
        f[:, c] = rng.uniform(-2.5, 2.5, size=5)
    f[:, 1:4] = rng.normal(size=(5, 3))
    m = motion_from_frames(f)
    sk = m.skeleton
    assert np.allclose(m.root_translation, f[:, 1:4])
    for t in range(5):
        R = chain(sk.root_axes, m.root_rotation[t])
        assert np.allclose(R, qmat(f[t, 4:8]), atol=1e-9)
        for name, c in QUATS.items():
            if name != "root":
                R = chain(sk.joints[sk.index(name)].axes, m.joint_angles[t, sk.dof_slice(name)])
                assert np.allclose(R, qmat(f[t, c:c + 4]), atol=1e-9), name
        for name, c in ANGLES.items():
            assert np.allclose(m.joint_angles[t, sk.dof_slice(name)], f[t, c]), name
    # a root turned a quarter about +y faces -z: the foot points that way
    g = still()
    g[0, 4:8] = quat([0, 1, 0], np.pi / 2)
    m = motion_from_frames(g)
    foot = pos(m, "right_foot_tip") - pos(m, "right_ankle")
    assert np.allclose(foot, [[0, -0.05, -0.1335]], atol=1e-6)


def test_mirror_swaps_the_sides_and_twice_is_the_original():
    m = motion_from_frames(walk())
    back = m.mirror()
    sk = m.skeleton
    swap = [sk.index(n.replace("left", "@").replace("right", "left").replace("@", "right"))
            for n in sk.names]
    S = np.diag([1.0, 1.0, -1.0])
    assert np.allclose(back.positions(), m.positions()[:, swap] @ S, atol=1e-9)
    assert np.allclose(back.mirror().positions(), m.positions(), atol=1e-9)


# ----------------------------------------------------------------------- frame rates
def test_frame_rate_from_the_durations():
    assert frame_rate(np.r_[[0.016666] * 9, 0.0]) == (60.0, True)
    assert frame_rate(np.r_[[0.033332] * 9, 0.0]) == (30.0, True)
    assert frame_rate(np.r_[[0.041667] * 4, 0.041667]) == (24.0, True)
    assert frame_rate(np.array([0.05])) == (20.0, True)
    assert frame_rate(np.array([0.0])) == (30.0, True)   # one frame, no duration
    assert frame_rate(np.r_[[0.02] * 5, 0.04, [0.02] * 4, 0.0]) == (50.0, False)


def test_uneven_frames_are_retimed_with_slerp():
    f = still(4, 0.1)
    f[:, 0] = [0.1, 0.2, 0.1, 0.0]                       # frames at 0, 0.1, 0.3, 0.4 s
    f[:, 1] = [0.0, 1.0, 3.0, 4.0]
    f[:, ANGLES["right_knee"]] = [0.0, -0.2, -0.6, -0.8]
    f[:, QUATS["chest"]:QUATS["chest"] + 4] = [quat([1, 0, 0], a) for a in (0, 0.2, 0.6, 0.8)]
    m = motion_from_frames(f)
    assert m.fps == 10.0 and m.n_frames == 5 and m.meta == {
        "loop": "none", "file_frames": 4, "retimed": True}
    assert np.allclose(m.root_translation[:, 0], [0, 1, 2, 3, 4])
    assert np.allclose(m.angle("right_knee_rz"), [0, -0.2, -0.4, -0.6, -0.8])
    sk = m.skeleton
    R = chain(sk.joints[sk.index("chest")].axes, m.joint_angles[2, sk.dof_slice("chest")])
    assert np.allclose(R, qmat(quat([1, 0, 0], 0.4)), atol=1e-9)   # halfway, by slerp


# ----------------------------------------------------------------------- the 21-joint body
def test_the_21_joint_body_stands_faces_forward_and_walks(tmp_path):
    m = read_motion(write_clip(tmp_path / "walk.txt", walk()))
    match = match_rig(m.skeleton)
    assert match.name == "deepmimic" and np.allclose(match.weights.sum(1), 1.0)
    b = body21(m)
    assert abs(b[:, [I["LA"], I["LF"], I["RA"], I["RF"]], 1].min()) < 0.02   # on the floor
    assert b[0, I["LH"], 0] > 0 > b[0, I["RH"], 0]              # the subject's left on +x
    assert b[0, I["LF"], 2] > b[0, I["LA"], 2]                  # toes ahead of the ankles
    assert b[-1, 0, 2] - b[0, 0, 2] > 1.0                       # walks forward (+Z)
    assert 0.80 < b[0, I["BUN"], 1] / 1.62 < 0.92               # head base near MMM's 0.87 H
    # a BVH written from it names its end points after their parents: the same body
    write_motion(m, tmp_path / "walk.bvh")
    again = read_motion(tmp_path / "walk.bvh")
    assert match_rig(again.skeleton).name == "deepmimic"
    assert np.allclose(positions21(again), positions21(m), atol=1e-6)


def test_folder_scan_takes_deepmimic_clips_and_no_other_text(tmp_path):
    write_clip(tmp_path / "walk.txt", walk(5))
    (tmp_path / "notes.txt").write_text("takes of the first day\n")
    (tmp_path / "args.txt").write_text("--motion_file data/motions/walk.txt\n")
    assert [p.name for p in motion_files(tmp_path)] == ["walk.txt"]
    assert is_motion_file(tmp_path / "x.bvh") and not is_motion_file(tmp_path / "gone.txt")


# ----------------------------------------------------------------------- malformed files
GOOD = still(2).tolist()
BAD = [
    (b"", "invalid JSON"),
    (b"--motion_file walk.txt\n", "not a DeepMimic motion"),
    (b"\xff\xfe\x00garbage", "not UTF-8"),
    (b"[[0.1, 0, 0]]", "found a JSON array"),
    (b"null", "found a JSON null"),
    (b'{"Loop": "wrap"}', "found an object with keys ['Loop']"),
    (b'{"Frames": []}', '"Frames" must be a non-empty list'),
    (b'{"Frames": {"a": 1}}', '"Frames" must be a non-empty list'),
    (json.dumps({"Frames": [GOOD[0][:43]]}).encode(), "43 numbers in a frame"),
    (json.dumps({"Frames": [GOOD[0] + [1.0]]}).encode(), "45 numbers in a frame"),
    (json.dumps({"Frames": [GOOD[0], ["x"] + GOOD[1][1:]]}).encode(),
     "(frame 1): a frame must be a list of numbers"),
    (json.dumps({"Frames": [GOOD[0], [True] + GOOD[1][1:]]}).encode(),
     "a frame must be a list of numbers"),
    (json.dumps({"Frames": [GOOD[0], 3]}).encode(), "a frame must be a list of numbers"),
    (json.dumps({"Frames": GOOD}).replace("0.0, 0.881416", "NaN, 0.881416", 1).encode(),
     "NaN is not a number JSON allows"),
    (json.dumps({"Frames": [[0.0, 1e300] + GOOD[0][2:]]}).encode(), "value out of range"),
    (json.dumps({"Frames": [GOOD[0][:8] + [0, 0, 0, 0] + GOOD[0][12:]]}).encode(),
     "the chest rotation (columns 9-12) is no quaternion of a rotation"),
    (json.dumps({"Frames": [[-0.1] + GOOD[0][1:]]}).encode(), "negative frame duration"),
    (json.dumps({"Frames": [[0.0] + GOOD[0][1:]] * 3}).encode(),
     "(frame 0): a frame before the last lasts 0 s"),
    (json.dumps({"Loop": 1, "Frames": GOOD}).encode(), '"Loop" must be "wrap" or "none"'),
    (b'{"Frames": ' + b"[" * 100 + b"]" * 100 + b"}", "nested deeper"),
]


@pytest.mark.parametrize("content, words", BAD)
def test_malformed_files_are_one_line_naming_the_file(tmp_path, content, words, capsys):
    path = tmp_path / "clip.txt"
    path.write_bytes(content)
    with pytest.raises(MotionFormatError) as err:
        read_motion(path)
    msg = str(err.value)
    assert msg.startswith(str(path)) and words in msg and "\n" not in msg, msg
    assert main(["info", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and words in lines[0] and "Traceback" not in lines[0]


def test_edited_clips_are_a_motion_or_one_clear_line(tmp_path):
    text = json.dumps({"Loop": "wrap", "Frames": walk(4).tolist()})
    rng = random.Random(5)
    path = tmp_path / "edited.txt"
    for k in range(200):
        i = rng.randrange(len(text))
        cut = text[:i] if k % 3 == 0 else text[:i] + rng.choice("{}[],.-e0 \"x") + text[i + 1:]
        path.write_text(cut)
        try:
            m = read_deepmimic(path)
        except MotionFormatError as exc:
            assert str(exc).startswith(str(path)) and "\n" not in str(exc)
        else:
            assert np.isfinite(m.positions()).all()


def test_other_extensions_still_go_to_their_readers(tmp_path):
    (tmp_path / "clip.json").write_text(json.dumps({"Frames": GOOD}))
    with pytest.raises(MotionFormatError, match=r"unknown motion file extension.*\.txt"):
        read_motion(tmp_path / "clip.json")
    with pytest.raises(MotionFormatError, match="not found"):
        read_motion(tmp_path / "gone.txt")


# ----------------------------------------------------------------------- the wheel's clips
def real_clips() -> list[Path]:
    clips = sorted(REAL.glob("humanoid3d_*.txt")) if REAL.is_dir() else []
    if not clips:
        pytest.skip(f"no DeepMimic clips in {REAL} (set MOTIONLANG_DEEPMIMIC)")
    return clips


def test_the_wheels_walk_stands_on_the_floor_and_walks_forward():
    path = REAL / "humanoid3d_walk.txt"
    if not path.is_file():
        pytest.skip(f"{path} not present (set MOTIONLANG_DEEPMIMIC)")
    m = read_motion(path)
    assert (m.n_frames, m.fps, m.meta["loop"]) == (39, 30.0, "wrap")
    p = m.positions()
    lowest = p[:, :, 1].min(axis=1)
    assert np.all(np.abs(lowest) < 0.03)                       # a foot on the floor always
    assert np.median(pos(m, "head_top")[:, 1]) > 1.5           # upright
    assert p[-1, 0, 0] - p[0, 0, 0] > 1.0                      # forward, along +x
    assert np.all(pos(m, "neck")[:, 1] > pos(m, "root")[:, 1] + 0.4)


def test_every_clip_of_the_wheel_reads_and_maps_to_the_body():
    for path in real_clips():
        m = read_motion(path)
        assert m.skeleton.name == "deepmimic:humanoid3d", path
        b = body21(m)
        assert np.isfinite(b).all() and b.shape == (m.n_frames, 21, 3), path
    other = REAL / "laikago_walk.txt"
    if other.is_file():
        with pytest.raises(MotionFormatError, match="20 numbers in a frame"):
            read_motion(other)

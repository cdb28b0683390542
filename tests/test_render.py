"""Rendering: files come out readable, with the frames and sizes asked for, atomically."""
import subprocess
import sys

import imageio.v2 as iio2
import imageio.v3 as iio
import numpy as np
import pytest

from helpers.data import ROOT, shared_file
from helpers.mocap import walker
from helpers.rigs import RIGS
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES
from motionlang.kinematics import Motion
from motionlang.rendering import animation as animation_mod
from motionlang.rendering.animation import render_animation
from motionlang.rendering.scene import (
    LEFT,
    RIGHT,
    TO_MPL,
    build_scene,
    camera_basis,
    contact_frames,
    footsteps,
    joint_sides,
    sample_times,
    scene_from_positions,
    view_azimuth,
)
from motionlang.rendering.strip import render_strip
from motionlang.rendering.trajectory import plot_trajectory


def expected_frames(motion: Motion, out_fps: float = 25.0) -> int:
    out_fps = min(out_fps, motion.fps)
    return int(np.floor((motion.n_frames - 1) / motion.fps * out_fps + 1e-9)) + 1


def no_leftovers(folder):
    return [p.name for p in folder.iterdir() if ".tmp" in p.name]


def test_gif_frames_and_size(tmp_path, tiny_motion):
    out = render_animation(tiny_motion, tmp_path / "a.gif", size=(3, 2), dpi=50)
    frames = iio.imread(out, index=None)
    assert frames.shape[0] == expected_frames(tiny_motion)
    assert frames.shape[1:3] == (100, 150)
    # something is drawn: not a blank canvas
    assert frames[0].std() > 5
    assert no_leftovers(tmp_path) == []


def test_mp4_two_motions_side_by_side(tmp_path):
    m = walker()
    out = render_animation([m, m.mirror()], tmp_path / "a.mp4", dpi=40, fps=10)
    reader = iio2.get_reader(out)
    frames = [f for f in reader]
    assert reader.get_meta_data()["fps"] == pytest.approx(10)
    assert len(frames) == expected_frames(m, 10)
    h, w = frames[0].shape[:2]
    assert (h, w) == (160, 320)  # two 4x4-inch panels at 40 dpi


def test_sample_times_real_time():
    idx = sample_times(378, 100.0, 25.0)
    assert len(idx) == 95 and idx[1] == 4 and idx[-1] == 376
    idx = sample_times(358, 120.0, 25.0)  # 4.8 source frames per output frame
    assert np.allclose(idx / 120.0, np.arange(len(idx)) / 25.0, atol=0.5 / 120)


def test_strip_width_grows_with_n_frames(tmp_path):
    m = walker(T=30, speed=0.0)  # in place: poses are spread apart by the layout
    w = [iio.imread(render_strip(m, tmp_path / f"s{n}.png", n_frames=n)).shape[1]
         for n in (2, 4, 8)]
    assert w[0] < w[1] < w[2]
    img = iio.imread(tmp_path / "s8.png")
    assert img.shape[0] > 100 and img[..., :3].std() > 5


def test_strip_rejects_other_extensions(tmp_path, tiny_motion):
    with pytest.raises(MotionlangError, match="png"):
        render_strip(tiny_motion, tmp_path / "s.jpg")
    assert list(tmp_path.iterdir()) == []


def test_failed_render_leaves_nothing(tmp_path, tiny_motion, monkeypatch):
    calls = []

    def broken_grab(canvas):
        calls.append(1)
        if len(calls) > 3:
            raise RuntimeError("disk on fire")
        return np.zeros((16, 16, 3), np.uint8)

    monkeypatch.setattr(animation_mod, "grab", broken_grab)
    for name in ("a.gif", "a.mp4"):
        calls.clear()
        with pytest.raises(RuntimeError):
            render_animation(tiny_motion, tmp_path / name)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(MotionlangError, match="unsupported"):
        render_animation(tiny_motion, tmp_path / "a.avi")
    assert list(tmp_path.iterdir()) == []


def test_frames_are_proper_rotation_and_sides():
    assert np.isclose(np.linalg.det(TO_MPL), 1.0)  # no mirroring
    assert np.allclose(TO_MPL @ [0, 1, 0], [0, 0, 1])  # canonical Y up -> matplotlib z up
    m = walker()
    sides = joint_sides(m)
    sk = m.skeleton
    assert sides[sk.index("LeftFoot")] == LEFT and sides[sk.index("RightLeg")] == RIGHT
    scene = build_scene(m)
    assert {sk.names[f] for f in scene.feet} == {"LeftFoot", "RightFoot"}
    assert scene.floor == pytest.approx(scene.points[:, scene.feet, 2].min())
    # walking along canonical +Z = matplotlib -y; the camera shows it going screen-right
    assert np.allclose(scene.forward, [0, -1], atol=1e-6)
    right, up, eye = camera_basis(view_azimuth(scene.forward), elev=12.0)
    assert right[:2] @ scene.forward > 0.8 and up[2] > 0.9


def test_contacts_low_and_slow():
    T, fps = 40, 20.0
    pos = np.zeros((T, 3, 3))  # root, foot A, foot B (canonical Y up)
    pos[:, 0] = [0, 1, 0]
    pos[:, 1] = [0.1, 0.0, 0.0]          # planted all along
    pos[:, 2, 0] = -0.1
    pos[:, 2, 2] = np.linspace(0, 2, T)  # slides at 1 m/s: never a contact
    pos[20:, 2, 1] = 0.0
    scene = scene_from_positions(pos, fps=fps)
    c = contact_frames(scene)
    assert c[1].all() and not c[2].any()
    steps = footsteps(scene)
    assert len(steps) == 1 and steps[0][0] == 1


def test_trajectory_plot(tmp_path):
    m = walker()
    out = plot_trajectory([m, m.positions()], tmp_path / "t.png", labels=["a", "b"])
    img = iio.imread(out)
    assert img.shape[0] > 200 and img.shape[1] > 200


def test_no_pyplot_state(tmp_path):
    # pyplot (and so a backend switch) is never touched; matplotlib.get_backend() itself
    # imports pyplot, so the check looks at sys.modules only
    code = ("import sys, numpy as np; from motionlang.rendering.strip import render_strip; from helpers.mocap "
            "import walker; render_strip(walker(), sys.argv[1]); "
            "print('matplotlib.pyplot' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "s.png")],
                         capture_output=True, text=True, check=True,
                         cwd=ROOT / "tests").stdout.split()
    assert out == ["False"]


def test_real_kit_walker_scene():
    from motionlang.formats.mmm import read_mmm

    m = read_mmm(shared_file("kitml/00001_mmm.xml"))
    scene = build_scene(m)          # the 21-joint body: a foot of each side
    assert sorted(KIT21_NAMES[f][0] for f in scene.feet) == [LEFT, RIGHT]
    # a 1.82 m subject upright on the floor; the 21-joint body ends at the upper neck
    assert 1.4 < scene.height < 1.7
    travel = scene.root[-1, :2] - scene.root[0, :2]
    assert travel @ scene.forward > 0.9 * np.linalg.norm(travel)
    # every left footstep lies left of the path (not mirrored): cross(travel, step) > 0
    steps = footsteps(scene)
    assert len(steps) >= 4
    for foot, xy in steps:
        nearest = np.argmin(np.linalg.norm(scene.root[:, :2] - xy, axis=1))
        rel = xy - scene.root[nearest, :2]
        side = np.sign(travel[0] * rel[1] - travel[1] * rel[0])
        assert side == (1 if KIT21_NAMES[foot][0] == LEFT else -1)


def test_animation_frames_lazy_and_counted():
    from motionlang.rendering.animation import animation_frames

    m = walker(T=30)
    fps, n, frames = animation_frames([m, m], fps=10, dpi=20, layout="overlay")
    got = list(frames)
    assert fps == 10 and n == len(got) == expected_frames(m, 10)
    assert got[0].shape == (80, 80, 3)  # overlay: one panel
    with pytest.raises(ValueError):
        animation_frames(m, fps=-1)


def test_kit21_scene_colours_sides_and_picks_one_foot_per_side(tmp_path):
    from motionlang.features.joint_map import KIT21_NAMES
    from motionlang.rendering.scene import kit21_scene
    T = 5
    pos = np.zeros((T, 21, 3))
    pos[:, :, 1] = 1.0                              # everything 1 m up ...
    for k, n in enumerate(KIT21_NAMES):
        pos[:, k, 0] = 0.1 if n.startswith("L") else (-0.1 if n[0] == "R" else 0.0)
    pos[:, KIT21_NAMES.index("LF"), 1] = 0.0        # ... except the two feet on the floor
    pos[:, KIT21_NAMES.index("RF"), 1] = 0.0
    pos[:, KIT21_NAMES.index("LMrot"), 1] = 0.05
    scene = kit21_scene(pos, 12.5)
    assert scene.feet == [KIT21_NAMES.index("LF"), KIT21_NAMES.index("RF")]
    sides = dict(zip((KIT21_NAMES[c] for _, c in scene.bones), scene.bone_sides))
    assert sides["LE"] == "L" and sides["RK"] == "R" and sides["BUN"] == "C"
    assert len(scene.bones) == 20 and scene.fps == 12.5 and scene.floor == 0.0
    with pytest.raises(ValueError):
        kit21_scene(pos[:, :20], 12.5)
    render_strip(scene, tmp_path / "s.png", n_frames=3)
    assert (tmp_path / "s.png").stat().st_size > 1000


@pytest.mark.parametrize("rig", sorted(RIGS))
def test_every_rig_is_drawn_upright_on_its_feet(rig, tmp_path):
    """Whatever a rig calls its joints (eyes, twist bones, a root on the floor), the drawing
    is the 21-joint body every command reads: its lowest points are the feet, its highest
    the head, and both sides are coloured."""
    from helpers.rigs import write
    from motionlang.formats import read_motion
    from motionlang.rendering.scene import LEFT, RIGHT, build_scene
    scene = build_scene(read_motion(write(RIGS[rig], tmp_path, T=20)))
    feet = {KIT21_NAMES.index(side + n) for side in "LR" for n in ("A", "Mrot", "F")}
    height = scene.points[..., 2]                # matplotlib frame: z up
    assert set(height.argmin(axis=1)) <= feet, rig
    assert set(height.argmax(axis=1)) <= {KIT21_NAMES.index("BUN")}, rig
    assert {LEFT, RIGHT} <= set(scene.bone_sides)
    assert scene.floor == pytest.approx(height.min())

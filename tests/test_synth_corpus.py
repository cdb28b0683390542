"""Synthetic corpus: motions (feet, floor, trajectory vs sentence), files on disk,
determinism, the KIT-ML loader, augmentation."""
import json

import numpy as np
import pytest
from experiments.lab.synth_quality import lowest_point_height, stance_sliding

from motionlang.datasets.synth.augment import change_speed, concat_samples, mirror_sample
from motionlang.datasets.synth.compose import build_motion, random_style
from motionlang.datasets.synth.corpus import generate_sample, write_corpus
from motionlang.datasets.synth.extract import extract_keys
from motionlang.datasets.synth.spec import Primitive
from motionlang.formats.mmm import read_mmm, write_mmm

WALKS = [
    Primitive("walk", count=6, direction="forward", speed="normal"),
    Primitive("walk", count=4, direction="backward", speed="fast"),
    Primitive("walk", count=4, direction="left", speed="slow"),
    Primitive("walk", count=11, direction="circle", side="right", speed="normal", angle=360),
    Primitive("run", count=8, direction="forward", speed="fast"),
]


def _build(prims, seed=0):
    rng = np.random.default_rng(seed)
    return build_motion(prims, random_style(rng), rng)


def _heading(motion, frame):
    """Canonical-frame (x, z) facing direction of the MMM root (local +Y)."""
    R = motion.global_transforms()[0][frame, 0]
    f = motion.skeleton.world @ R @ np.array([0.0, 1.0, 0.0])
    return f[[0, 2]] / np.linalg.norm(f[[0, 2]])


@pytest.mark.parametrize("prim", WALKS, ids=lambda p: f"{p.action}-{p.direction}")
def test_gait_feet_do_not_slide_and_touch_the_floor(prim, tmp_path):
    motion, prims, _ = _build([prim])
    write_mmm(motion, tmp_path / "m.xml")  # measure what a user reads back
    back = read_mmm(tmp_path / "m.xml")
    seg = slice(prims[0].start, prims[0].end)
    slips = stance_sliding(back, frames=seg)
    assert len(slips) >= prim.count  # every step makes a contact
    assert np.mean(slips) < 0.02, slips
    low = lowest_point_height(back)[seg]
    if prim.action == "walk":  # walking: always a foot on the floor, no floating
        assert low.max() < 0.01
    else:  # running: flight phases, but short and low
        assert 0.01 < low.max() < 0.3


@pytest.mark.parametrize("direction", ["forward", "backward", "left", "right"])
def test_root_trajectory_matches_direction_and_step_count(direction):
    prim = Primitive("walk", count=5, direction=direction, speed="normal")
    motion, prims, _ = _build([prim], seed=3)
    pos = motion.positions()[:, 0]
    disp = (pos[prims[0].end - 1] - pos[prims[0].start])[[0, 2]]
    f = _heading(motion, prims[0].start)
    left = np.array([f[1], -f[0]])  # canonical frame: Y up, +x is the body's left at f=+z
    along = {"forward": f, "backward": -f, "left": left, "right": -left}[direction]
    assert disp @ along > 0.5 and abs(disp @ np.array([along[1], -along[0]])) < 0.15
    # N placements = N contacts starting inside the segment (plus the standing ones)
    slips = stance_sliding(motion, frames=slice(prims[0].start, prims[0].end))
    assert len(slips) == prim.count + 2


@pytest.mark.parametrize("side,sign", [("left", 1.0), ("right", -1.0)])
def test_turns_and_circles_go_the_stated_way(side, sign):
    motion, prims, _ = _build([Primitive("turn", side=side, angle=90)], seed=1)
    f0, f1 = _heading(motion, prims[0].start), _heading(motion, prims[0].end - 1)
    # canonical frame Y up: turning left is counter-clockwise seen from above (+y),
    # i.e. the cross product (x, z) components gives a positive turn about +y ...
    turn = np.degrees(np.arctan2(f0[1] * f1[0] - f0[0] * f1[1], f0 @ f1))
    assert abs(abs(turn) - 90) < 10
    assert np.sign(turn) == sign
    motion, prims, _ = _build([Primitive("walk", side=side, count=12, direction="circle",
                                         speed="normal", angle=360)], seed=2)
    pos = motion.positions()[:, 0][:, [0, 2]]
    seg = pos[prims[0].start:prims[0].end]
    assert np.linalg.norm(seg[-1] - seg[0]) < 0.3  # back where it started
    assert np.ptp(seg[:, 0]) > 1.0  # ... after going round
    f = _heading(motion, prims[0].start)
    v = seg[20] - seg[0]
    assert np.sign(f[1] * v[0] - f[0] * v[1]) == sign or np.linalg.norm(v) < 0.01


def test_corpus_is_deterministic_and_kit_layout(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    ids = write_corpus(a, 3, seed=7, workers=1, show_progress=False)
    write_corpus(b, 3, seed=7, workers=1, show_progress=False)
    assert ids == ["00001", "00002", "00003"]
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(f"{i}_{k}" for i in ids
                           for k in ("mmm.xml", "annotations.json", "meta.json"))
    for n in names:
        assert (a / n).read_bytes() == (b / n).read_bytes(), n
    c = tmp_path / "c"
    write_corpus(c, 3, seed=8, workers=1, show_progress=False)
    assert (a / "00001_mmm.xml").read_bytes() != (c / "00001_mmm.xml").read_bytes()
    for i in ids:
        texts = json.loads((a / f"{i}_annotations.json").read_text())
        meta = json.loads((a / f"{i}_meta.json").read_text())
        assert 2 <= len(texts) <= 4 and len(set(texts)) == len(texts)
        assert meta["source"]["seed"] == 7 and meta["primitives"]
        for text, stated in zip(texts, meta["annotation_params"]):
            got = extract_keys(text)
            want = [tuple(p[f] for f in ("action", "side", "count", "direction", "speed",
                                         "angle")) for p in stated]
            assert got == want


def test_worker_count_does_not_change_output(tmp_path):
    write_corpus(tmp_path / "one", 8, seed=1, workers=1, show_progress=False)
    write_corpus(tmp_path / "two", 8, seed=1, workers=2, show_progress=False)
    for p in (tmp_path / "one").iterdir():
        assert p.read_bytes() == (tmp_path / "two" / p.name).read_bytes()


def test_kitml_loader_reads_the_corpus(tmp_path):
    kitml = pytest.importorskip("motionlang.datasets.kitml")
    write_corpus(tmp_path, 3, seed=2, workers=1, show_progress=False)
    records = kitml.load_kitml(tmp_path)
    assert [r.id for r in records] == ["00001", "00002", "00003"]
    s = generate_sample(2, 1)
    rec = records[1]
    assert rec.annotations == s.annotations
    m = rec.load_motion()
    assert m.n_frames == s.motion.n_frames and m.fps == 100
    assert np.allclose(m.joint_angles, s.motion.joint_angles, atol=1e-5)
    assert abs(m.meta["height"] - s.style["height"]) < 1e-3


def test_mirror_twice_restores_motion_and_text():
    s = generate_sample(0, 4)
    m1, t1, p1 = mirror_sample(s.motion, s.annotations, s.primitives)
    m2, t2, p2 = mirror_sample(m1, t1, p1)
    assert t2 == s.annotations
    assert [p.to_dict() for p in p2] == [p.to_dict() for p in s.primitives]
    assert np.allclose(m2.joint_angles, s.motion.joint_angles)
    assert np.allclose(m2.root_translation, s.motion.root_translation)
    # the mirrored body is the mirror image: left foot where the right one was, reflected
    pos, mpos = s.motion.positions(), m1.positions()
    sk = s.motion.skeleton
    lf, rf = sk.index("LeftFootHeight_joint"), sk.index("RightFootHeight_joint")
    reflect = sk.world @ sk.mirror @ sk.world.T
    assert np.allclose(mpos[:, lf], pos[:, rf] @ reflect.T, atol=1e-6)


def test_speed_change_relabels_only_known_speeds():
    prim = Primitive("walk", count=4, direction="forward", speed="slow")
    motion, prims, _ = _build([prim])
    rng = np.random.default_rng(0)
    fast, texts, new = change_speed(motion, 1.5, ["x", "y"], prims, rng)
    assert abs(fast.n_frames - motion.n_frames / 1.5) <= 2
    assert new[0].speed == "normal" and new[0].end == round(prims[0].end / 1.5)
    assert all(extract_keys(t)[0][4] in (None, "normal") for t in texts)
    # free text: unchanged when it states no speed, refused when it does
    assert change_speed(motion, 1.5, ["A person walks forward."])[1] == \
        ["A person walks forward."]
    assert change_speed(motion, 1.5, ["A person walks slowly."]) is None


def test_concatenation_continues_where_the_first_ends():
    a, b = generate_sample(0, 2), generate_sample(0, 3)
    m, texts, prims = concat_samples(a.motion, b.motion, a.annotations, b.annotations,
                                     a.primitives, b.primitives)
    T = a.motion.n_frames
    assert m.n_frames == T + b.motion.n_frames
    root = m.positions()[:, 0]
    assert np.linalg.norm(root[T] - root[T - 1]) < 0.05
    assert len(prims) == len(a.primitives) + len(b.primitives)
    assert prims[len(a.primitives)].start == b.primitives[0].start + T
    assert ", then " in texts[0]


def test_cli_data_synth(tmp_path, capsys):
    from motionlang.cli.main import main

    out = tmp_path / "corpus"
    assert main(["data", "synth", "--out", str(out), "--n", "2", "--seed", "4",
                 "--workers", "1"]) == 0
    assert sorted(p.name for p in out.glob("*_mmm.xml")) == ["00001_mmm.xml", "00002_mmm.xml"]
    assert "wrote 2 motions" in capsys.readouterr().out
    assert main(["data", "synth", "--out", str(out), "--n", "0"]) == 2
    assert "argument --n: must be an integer >= 1" in capsys.readouterr().err


@pytest.mark.parametrize("index", [0, 1, 5, 12])
def test_samples_are_smooth_and_within_joint_limits(index):
    from motionlang.datasets.synth.track import dof_limits

    s = generate_sample(3, index)
    m = s.motion
    assert np.abs(np.diff(m.joint_angles, axis=0)).max() < 0.35  # rad per 10 ms
    assert np.linalg.norm(np.diff(m.root_translation, axis=0), axis=1).max() < 0.07
    lim = dof_limits()
    for j, name in enumerate(m.skeleton.dof_names):
        lo, hi = lim[name]
        # ankles may exceed the model's range a little when flat on the floor in a squat
        tol = 0.25 if name[1] == "A" else 0.12
        assert lo - tol <= m.joint_angles[:, j].min() and m.joint_angles[:, j].max() <= hi + tol, name
    # the primitives tile the motion in order and lie inside it
    body = [p for p in s.primitives if p.layer == "body"]
    assert all(a.end == b.start for a, b in zip(body, body[1:]))
    assert 0 < body[0].start and body[-1].end < m.n_frames


def test_mirror_augmentation_on_real_kitml_motion():
    from helpers.data import shared_file

    m = read_mmm(shared_file("kitml/00001_mmm.xml"))
    m1, t1, _ = mirror_sample(m, ["A person turns left and walks forwards."])
    assert t1 == ["A person turns right and walks forwards."]
    m2, t2, _ = mirror_sample(m1, t1)
    assert t2 == ["A person turns left and walks forwards."]
    assert np.allclose(m2.joint_angles, m.joint_angles)
    assert np.allclose(m2.root_rotation, m.root_rotation)
    assert not np.allclose(m1.joint_angles, m.joint_angles)


def test_stated_speed_orders_walking_speed():
    speeds = []
    for sp in ("slow", "normal", "fast"):
        rng = np.random.default_rng(9)
        style = random_style(rng)
        m, prims, _ = build_motion([Primitive("walk", count=6, direction="forward",
                                              speed=sp)], style, rng)
        root = m.positions()[prims[0].start:prims[0].end, 0][:, [0, 2]]
        speeds.append(np.linalg.norm(root[-1] - root[0]) / ((len(root) - 1) / m.fps))
    assert speeds[0] < speeds[1] < speeds[2]
    assert 0.4 < speeds[0] and speeds[2] < 2.2  # m/s incl. start and stop

"""glTF / GLB export: what a glTF reader plays back is motionlang's own forward kinematics."""
from __future__ import annotations

import json

import numpy as np
import pytest

from helpers.mocap import synthetic_mmm
from helpers.rigs import RIGS, write
from motionlang.api import write_result
from motionlang.cli.main import main
from motionlang.errors import MotionFormatError
from motionlang.features.joint_map import KIT21_NAMES, positions21
from motionlang.formats import read_motion, write_motion
from motionlang.formats.gltf_read import read_gltf_animation
from motionlang.rendering.output import part_lengths, rig_differences


@pytest.mark.parametrize("ext", [".glb", ".gltf"])
def test_a_z_up_mmm_motion_plays_back_as_its_own_kinematics(tmp_path, ext):
    # MMM: a Z-up source frame, millimetre file units and fixed segment rotations (pre),
    # so every conversion the writer does is exercised
    motion = synthetic_mmm(T=25, fps=100.0)
    out = write_motion(motion, tmp_path / f"walk{ext}")
    back = read_gltf_animation(out)
    sk = motion.skeleton
    assert back.names[:len(sk)] == sk.names
    assert list(back.parents[:len(sk)]) == list(sk.parents)
    assert back.positions.shape[0] == 25 and back.fps == pytest.approx(100.0)
    assert np.allclose(back.times, np.arange(25) / 100.0, atol=1e-6)
    assert back.skin_joints == list(range(len(sk)))
    err = np.abs(back.positions[:, :len(sk)] - motion.positions()).max()
    assert err < 1e-5, f"{err * 1000:.4f} mm"   # float32 storage, metres
    assert back.positions[0, 0, 1] > 0.5   # Y up: the pelvis is above the floor


def test_the_glb_holds_a_skinned_mesh_and_names_the_animation(tmp_path):
    import pygltflib

    motion = synthetic_mmm(T=5, fps=100.0)
    gltf = pygltflib.GLTF2.load(str(write_motion(motion, tmp_path / "m.glb")))
    mesh_nodes = [n for n in gltf.nodes if n.mesh is not None]
    assert len(mesh_nodes) == 1 and mesh_nodes[0].skin == 0
    prim = gltf.meshes[0].primitives[0]
    assert gltf.accessors[prim.attributes.POSITION].count > 0
    assert gltf.accessors[prim.indices].count % 3 == 0
    assert gltf.animations[0].name == motion.name
    assert gltf.animations[0].extras == {"fps": 100.0, "frames": 5}
    assert gltf.asset.version == "2.0"


def test_a_user_rig_keeps_its_names_and_rest_pose_in_metres(tmp_path):
    bvh = write(RIGS["bandai"], tmp_path, T=12)
    motion = read_motion(bvh)
    back = read_gltf_animation(write_motion(motion, tmp_path / "rig.gltf"))
    assert back.names[:len(motion.skeleton)] == motion.skeleton.names
    assert np.abs(back.positions[:, :len(motion.skeleton)] - motion.positions()).max() < 1e-5
    with open(tmp_path / "rig.gltf", encoding="utf-8") as fh:
        assert json.load(fh)["buffers"][0]["uri"].startswith("data:")   # one file


def test_write_result_fits_positions_on_the_body_for_a_glb(tmp_path):
    motion = read_motion(write(RIGS["bandai"], tmp_path, T=10))
    p21 = positions21(motion)
    note = write_result(p21, tmp_path / "gen.glb", fps=30.0)
    back = read_gltf_animation(tmp_path / "gen.glb")
    assert "from the generated ones" in note
    assert back.names[:21] == list(KIT21_NAMES) and back.fps == pytest.approx(30.0)
    assert np.abs(back.positions[:, :21] - p21).max() < 0.1


def test_convert_writes_glb_and_refuses_a_bad_path_with_one_line(tmp_path, capsys):
    bvh = write(RIGS["bandai"], tmp_path, T=6)
    assert main(["convert", str(bvh), str(tmp_path / "out.glb")]) == 0
    assert read_gltf_animation(tmp_path / "out.glb").positions.shape[0] == 6
    capsys.readouterr()
    bad = tmp_path / "no" / "such" / "out.glb"
    (tmp_path / "no").write_text("a file, not a folder")
    assert main(["convert", str(bvh), str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err and "out.glb" in err
    assert not bad.exists()


def test_a_broken_glb_is_one_error_naming_the_file(tmp_path):
    bad = tmp_path / "broken.glb"
    bad.write_bytes(b"glTF\x02\x00\x00\x00garbage")
    with pytest.raises(MotionFormatError, match="broken.glb"):
        read_gltf_animation(bad)


def _edited_glb(path, edit) -> bytes:
    """The GLB in ``path`` with its JSON chunk passed through ``edit`` (lengths kept)."""
    data = path.read_bytes()
    n = int.from_bytes(data[12:16], "little")
    doc = json.loads(data[20:20 + n])
    edit(doc)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + n:]
    body = len(text).to_bytes(4, "little") + b"JSON" + text + rest
    return data[:8] + (12 + len(body)).to_bytes(4, "little") + body


@pytest.mark.parametrize("edit, needle", [
    (lambda d: [v.update(byteOffset=-8) for v in d["bufferViews"]], "a negative offset"),
    (lambda d: d["animations"][0].setdefault("extras", {}).update(fps="fast"),
     "extras.fps must be a positive number, got 'fast'"),
    (lambda d: d["animations"][0].setdefault("extras", {}).update(fps=-3),
     "extras.fps must be a positive number"),
])
def test_a_damaged_glb_field_is_one_line(tmp_path, edit, needle, capsys):
    good = tmp_path / "gen.glb"
    write_result(positions21(read_motion(write(RIGS["bandai"], tmp_path, T=10))), good,
                 fps=30.0)
    bad = tmp_path / "bad.glb"
    bad.write_bytes(_edited_glb(good, edit))
    with pytest.raises(MotionFormatError, match=needle):
        read_gltf_animation(bad)
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad.glb" in err and needle.split(",")[0] in err


def test_convert_onto_a_users_rig(tmp_path, capsys):
    # a walk on the Bandai rig retargeted onto a Mixamo-named character, as GLB and BVH
    walk = write(RIGS["bandai"], tmp_path, T=12)
    rig = write(RIGS["mixamo"], tmp_path, T=2)
    rig_names = read_motion(rig).skeleton.names
    assert main(["convert", str(walk), str(tmp_path / "on_rig.glb"), "--rig", str(rig)]) == 0
    back = read_gltf_animation(tmp_path / "on_rig.glb")
    assert back.names[:len(rig_names)] == rig_names and back.positions.shape[0] == 12
    assert main(["convert", str(walk), str(tmp_path / "on_rig.bvh"), "--rig", str(rig)]) == 0
    moved = read_motion(tmp_path / "on_rig.bvh")
    assert moved.skeleton.names == rig_names
    # the body's path survives the retargeting
    a, b = positions21(read_motion(walk)), positions21(moved)
    assert np.abs((a[-1, 0] - a[0, 0]) - (b[-1, 0] - b[0, 0]))[[0, 2]].max() < 0.05
    capsys.readouterr()
    assert main(["convert", str(walk), str(tmp_path / "x.bvh"), "--rig-joint-map",
                 str(tmp_path / "m.json")]) == 2
    assert capsys.readouterr().err.strip().endswith("--rig-joint-map needs --rig")
    assert not (tmp_path / "x.bvh").exists()


@pytest.mark.parametrize("ext", [".glb", ".gltf"])
def test_read_motion_takes_a_glb_back_as_a_motion(tmp_path, ext):
    """What motionlang writes reads back: the same joints, frame rate and body positions
    (joint angles fitted to the played positions; float32 storage)."""
    motion = synthetic_mmm(T=25, fps=100.0)
    out = write_motion(motion, tmp_path / f"walk{ext}")
    back = read_motion(out)
    assert back.source_format == "gltf" and back.fps == pytest.approx(100.0)
    assert back.n_frames == 25 and back.skeleton.names == motion.skeleton.names
    err = np.abs(positions21(back) - positions21(motion)).max()
    assert err < 1e-3, f"{err * 1000:.3f} mm"
    assert main(["info", str(out)]) == 0


def test_a_glb_without_pygltflib_is_one_line(tmp_path, monkeypatch, capsys):
    import builtins
    out = write_motion(synthetic_mmm(T=5, fps=100.0), tmp_path / "w.glb")
    real = builtins.__import__

    def no_gltf(name, *args, **kwargs):
        if name == "pygltflib":
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_gltf)
    assert main(["info", str(out)]) == 2
    err = capsys.readouterr().err
    assert "w.glb" in err and "motionlang[export]" in err and len(err.splitlines()) == 1


def test_the_note_of_a_rig_says_which_parts_differ(tmp_path):
    p21 = positions21(read_motion(write(RIGS["bandai"], tmp_path, T=10)))
    assert rig_differences(p21, p21) == ("its legs, arms and trunk are within 3% of the "
                                         "generated body's")
    small = p21 * 0.9
    assert rig_differences(p21, small) == ("its legs are 10% shorter, arms 10% shorter and "
                                           "trunk 10% shorter than the generated body's")
    longer_arms = p21.copy()
    for side in ("L", "R"):   # the forearm 20 cm longer
        e, w = KIT21_NAMES.index(side + "E"), KIT21_NAMES.index(side + "W")
        bone = longer_arms[:, w] - longer_arms[:, e]
        longer_arms[:, w] += 0.2 * bone / np.linalg.norm(bone, axis=-1, keepdims=True)
    arms = part_lengths(p21)["arms"]
    said = rig_differences(p21, longer_arms)
    assert said == f"its arms are {0.2 / arms:.0%} longer than the generated body's", said
    no_trunk = np.ones(21, dtype=bool)
    no_trunk[KIT21_NAMES.index("BT")] = False   # a rig that does not map it: not compared
    assert "trunk" not in part_lengths(p21, no_trunk)
    # on a rig: the note names the parts and how far the joints lie
    rig = read_motion(write(RIGS["mixamo"], tmp_path, T=4))
    note = write_result(p21, tmp_path / "on_rig.bvh", fps=30.0, rig=rig)
    assert "than the generated body's, so its body joints lie" in note or \
        "of the generated body's, so its body joints lie" in note, note
    assert "mm from the generated ones on average" in note

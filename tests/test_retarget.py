"""Body positions -> a Motion on a user's rig (kinematics.retarget): a rig's own motion comes
back exactly (BVH rig with bones along X, and a rig with fixed pre/post rotations in a Z-up
frame), another body's motion keeps the rig's bones and the source's directions and floor,
no twist flips, the BVH keeps the rig's names and unit, and the Bandai round trip."""

import numpy as np
import pytest

from helpers.data import bandai_takes, shared_file
from motionlang.errors import MotionlangError, SkeletonError
from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS, kit21_weights, positions21
from motionlang.formats import read_motion
from motionlang.formats.bvh import read_bvh, write_bvh
from motionlang.kinematics import Joint, Motion, Skeleton
from motionlang.kinematics.retarget import retarget
from motionlang.kinematics.rotations import chain, matrix_to_chain

ZXY = np.eye(3)[[2, 0, 1]]
K = {n: i for i, n in enumerate(KIT21_NAMES)}
# a standing body in CMU-BVH naming, metres, Y up, facing +Z, left = +X: (name, parent, bone)
_HALF = [("{s}HipJoint", "Hips", (0.02, -0.03, 0)),
         ("{S}UpLeg", "{s}HipJoint", (0.07, -0.04, 0.01)),
         ("{S}Leg", "{S}UpLeg", (0, -0.42, 0.01)), ("{S}Foot", "{S}Leg", (0, -0.41, -0.02)),
         ("{S}ToeBase", "{S}Foot", (0, -0.06, 0.12)),
         ("{S}ToeBase_end", "{S}ToeBase", (0, 0, 0.05)),
         ("{S}Shoulder", "Spine1", (0.03, 0.10, 0)), ("{S}Arm", "{S}Shoulder", (0.14, 0, -0.01)),
         ("{S}ForeArm", "{S}Arm", (0, -0.28, 0)), ("{S}Hand", "{S}ForeArm", (0, -0.25, 0.01)),
         ("{S}Hand_end", "{S}Hand", (0, -0.08, 0))]
STAND = [("Hips", None, (0, 0, 0)), ("LowerBack", "Hips", (0, 0.06, -0.01)),
         ("Spine", "LowerBack", (0, 0.11, 0)), ("Spine1", "Spine", (0, 0.12, 0.01)),
         ("Neck", "Spine1", (0, 0.13, 0.01)), ("Neck1", "Neck", (0, 0.05, 0.01)),
         ("Head", "Neck1", (0, 0.05, 0)), ("Head_end", "Head", (0, 0.15, 0))] + [
    (n.format(s=s, S=S), p.format(s=s, S=S), (sign * b[0], b[1], b[2]))
    for s, S, sign in (("L", "Left", 1), ("R", "Right", -1)) for n, p, b in _HALF]
IN_BETWEEN = ("LHipJoint", "RHipJoint", "Spine1", "LeftShoulder", "RightShoulder", "Neck1")


def _frame_along(d: np.ndarray) -> np.ndarray:
    """A rotation taking +X to the unit vector d (3,)."""
    y = np.cross([0.3, 0.2, 1.0], d)
    y /= np.linalg.norm(y)
    return np.stack([d, y, np.cross(d, y)], axis=1)


def _walk_rig(T=60, fps=30.0, seed=0) -> Motion:
    """A walking-ish motion on STAND re-expressed with every bone along its parent's local X
    (like Bandai: the zero-rotation pose is not a standing one); unmapped in-between joints
    keep a constant rotation."""
    names = [n for n, _, _ in STAND]
    parents = [-1] + [names.index(p) for _, p, _ in STAND[1:]]
    kids = [[c for c in range(len(names)) if parents[c] == j] for j in range(len(names))]
    Q = [_frame_along(np.array(STAND[k[0]][2]) / np.linalg.norm(STAND[k[0]][2])) if k else
         np.eye(3) for k in kids]
    rng = np.random.default_rng(seed)
    ph = 2 * np.pi * np.arange(T)[:, None] / fps
    joints, angles = [], []
    for j, (n, _, bone) in enumerate(STAND):
        q = parents[j]
        offset = Q[q].T @ np.array(bone) if j else np.zeros(3)
        if not kids[j]:
            joints.append(Joint(n, q, offset))
            continue
        amp = 0.0 if n in IN_BETWEEN else rng.uniform(0.1, 0.5, 3)
        local = chain(ZXY, rng.uniform(-0.2, 0.2, 3) + amp * np.sin(ph + rng.uniform(0, 6, 3)))
        if j:   # the same world pose with frames turned by Q: L' = Q_parent^T L Q
            angles.append(np.unwrap(matrix_to_chain(Q[q].T @ local @ Q[j], ZXY), axis=0))
        else:
            root = matrix_to_chain(local @ Q[0], ZXY)
        joints.append(Joint(n, q, offset, axes=ZXY if j else np.zeros((0, 3)),
                            dof_names=tuple(f"{n}_{c}rotation" for c in "ZXY") if j else ()))
    sk = Skeleton(joints, root_axes=ZXY, file_unit=0.01, name="walker")
    t = np.arange(T) / fps
    trans = np.stack([0.05 * np.sin(ph[:, 0]), 0.93 + 0.02 * np.cos(2 * ph[:, 0]), 1.2 * t], 1)
    return Motion(sk, fps, trans, np.unwrap(root, axis=0), np.concatenate(angles, axis=1),
                  name="walker", source_format="bvh",
                  meta={"bvh_root_channels": ["Xposition", "Yposition", "Zposition",
                                              "Zrotation", "Xrotation", "Yrotation"]})


@pytest.fixture
def rig(tmp_path) -> Motion:
    """The walker as a user's file: written as BVH (centimetres) and read back."""
    write_bvh(_walk_rig(), tmp_path / "rig.bvh")
    return read_bvh(tmp_path / "rig.bvh")


def _mapped(motion: Motion, W: np.ndarray) -> np.ndarray:
    return np.einsum("kj,tjc->tkc", W, motion.positions())


def _angle(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Radians between vectors (..., 3)."""
    cos = np.sum(u * v, -1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
    return np.arccos(np.clip(cos, -1.0, 1.0))


def _turns(motion: Motion) -> np.ndarray:
    """(T-1, J) radians each joint's local rotation turns from one frame to the next."""
    G, _ = motion.global_transforms()
    par = np.maximum(motion.skeleton.parents, 0)
    L = np.where((motion.skeleton.parents < 0)[None, :, None, None], G,
                 np.swapaxes(G[:, par], -1, -2) @ G)
    step = np.swapaxes(L[:-1], -1, -2) @ L[1:]
    return np.arccos(np.clip((np.trace(step, axis1=-2, axis2=-1) - 1) / 2, -1, 1))


def test_a_rigs_own_motion_comes_back(rig):
    assert rig.skeleton.joints[rig.skeleton.index("LeftArm")].offset[1:] == pytest.approx(0)
    _, W = kit21_weights(rig.skeleton)
    p = _mapped(rig, W)
    out = retarget(p, rig.fps, rig, weights=W)
    assert out.skeleton is rig.skeleton and out.source_format == "bvh"
    assert "path" not in out.meta and out.meta["rig"] == rig.meta["path"]
    assert np.abs(_mapped(out, W) - p).max() < 1e-6


def test_fixed_rotations_and_a_z_up_frame(rig):
    # the walker with ASF-style fixed rotations around X Y Z chains, in a Z-up source frame
    sk0, rng = rig.skeleton, np.random.default_rng(1)
    world = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])      # source Z up -> canonical Y up
    joints, angles = [], []
    G0, _ = rig.global_transforms()
    for j, jt in enumerate(sk0.joints):
        pre = chain(np.eye(3), rng.uniform(-1, 1, 3))
        L = world.T @ (np.swapaxes(G0[:, jt.parent], -1, -2) @ G0[:, j] if j else G0[:, 0]) @ world
        if jt.ndof:
            angles.append(np.unwrap(matrix_to_chain(pre.T @ L @ pre, np.eye(3)), axis=0))
        pre = pre if jt.ndof else np.eye(3)
        joints.append(Joint(jt.name, jt.parent, world.T @ jt.offset, pre=pre, post=pre.T,
                            axes=np.eye(3)[:3 if jt.ndof else 0]))
    joints[0] = Joint("Hips", -1, np.zeros(3))
    sk = Skeleton(joints, world=world, root_axes=np.eye(3)[[2, 1, 0]], name="zup")
    root = matrix_to_chain(world.T @ G0[:, 0] @ world, sk.root_axes)
    m = Motion(sk, rig.fps, rig.root_translation @ world, root, np.concatenate(angles, axis=1))
    np.testing.assert_allclose(m.positions(), rig.positions(), atol=1e-9)
    _, W = kit21_weights(sk)
    p = _mapped(m, W)
    assert np.abs(_mapped(retarget(p, m.fps, m, weights=W), W) - p).max() < 1e-6


def test_another_body_on_the_rig(rig, tmp_path):
    src = read_motion(shared_file("cmu35/35_01.amc"))[::4]          # 30 fps
    p = positions21(src)
    _, W = kit21_weights(rig.skeleton)
    out = retarget(p, src.fps, rig, weights=W)
    q, q0 = _mapped(out, W), _mapped(rig, W)[0]
    for a, b in (("LS", "LE"), ("LE", "LW"), ("RH", "RK"), ("RK", "RA"), ("LA", "LF")):
        bone, rest = q[:, K[b]] - q[:, K[a]], q0[K[b]] - q0[K[a]]
        # the rig's own bone lengths, pointing where the source's bones point
        np.testing.assert_allclose(np.linalg.norm(bone, axis=-1), np.linalg.norm(rest),
                                   rtol=1e-9)
        want = p[:, K[b]] - p[:, K[a]]
        assert _angle(bone, want).max() < 1e-6
    # the trunk is matched in least squares: within a few degrees
    trunk = _angle(q[:, K["BLN"]] - q[:, K["root"]], p[:, K["BLN"]] - p[:, K["root"]])
    assert np.degrees(trunk.max()) < 10
    # the rig's lowest drawn points (toe tips below its mapped toes) on the source's floor,
    # the feet there at every step, and no twist flips
    lowest = lambda x: x[..., 1].min(axis=1)                      # noqa: E731
    assert abs(np.percentile(lowest(out.positions()), 5) - np.percentile(lowest(p), 5)) < 1e-6
    assert np.abs(lowest(q) - lowest(p)).max() < 0.05
    bones = p[:, 1:] - p[:, list(KIT21_PARENTS[1:])]
    bones /= np.linalg.norm(bones, axis=-1, keepdims=True)
    fastest = np.arccos(np.clip(np.sum(bones[1:] * bones[:-1], -1), -1, 1)).max()
    assert _turns(out).max() < 1.2 * fastest            # 0.59 rad: toe-off at 30 fps
    # (c) written as BVH on the rig's layout and read back: the same joints
    write_bvh(out, tmp_path / "out.bvh")
    back = read_bvh(tmp_path / "out.bvh")
    assert back.skeleton.names == rig.skeleton.names and back.skeleton.file_unit == 0.01
    np.testing.assert_allclose(back.positions(), out.positions(), atol=1e-5)


def _held(rig: Motion, W: np.ndarray, T: int) -> np.ndarray:
    """The rig's first mapped pose held for T frames."""
    return np.repeat(_mapped(rig, W)[:1], T, axis=0)


def _wave_travel(rig: Motion, W: np.ndarray, path, T: int = 60) -> np.ndarray:
    """The rig's first pose with the right upper arm out to the side and the forearm waving,
    retargeted, written to ``path`` and read back: (21,) metres each body point travels."""
    p = _held(rig, W, T)
    l1 = np.linalg.norm(p[0, K["RE"]] - p[0, K["RS"]])
    l2 = np.linalg.norm(p[0, K["RW"]] - p[0, K["RE"]])
    side = np.cross(p[0, K["BLN"]] - p[0, K["root"]], p[0, K["LS"]] - p[0, K["RS"]])
    out = p[0, K["RS"]] - p[0, K["LS"]]                  # towards the right
    out /= np.linalg.norm(out)
    up = np.cross(side, out)
    up /= np.linalg.norm(up)
    p[:, K["RE"]] = p[:, K["RS"]] + l1 * out
    wave = 0.6 * np.sin(2 * np.pi * np.arange(T) / 15)[:, None]
    p[:, K["RW"]] = p[:, K["RE"]] + l2 * (np.sin(wave) * out + np.cos(wave) * up)
    write_bvh(retarget(p, 30.0, rig, weights=W), path)
    back = read_bvh(path)       # its own map: a still Hips may read back below joint_Root
    q = _mapped(back, kit21_weights(back.skeleton)[1])
    return np.linalg.norm(np.diff(q, axis=0), axis=-1).sum(axis=0)


def test_waving_right_arm_reads_back_moving_most(rig, tmp_path):
    _, W = kit21_weights(rig.skeleton)
    travel = _wave_travel(rig, W, tmp_path / "wave.bvh")
    assert KIT21_NAMES[int(np.argmax(travel))] == "RW"
    assert np.delete(travel, [K["RE"], K["RW"]]).max() < 1e-6


def test_no_twist_flip_with_the_arm_overhead(rig):
    # the left upper arm swings out and up to 5 degrees from vertical, then circles there:
    # a swing from the hanging template would spin the arm about itself once per circle
    _, W = kit21_weights(rig.skeleton)
    up = np.concatenate([np.linspace(0, np.radians(175), 40), np.full(40, np.radians(175))])
    around = np.concatenate([np.zeros(40), np.linspace(0, 2 * np.pi, 40)])
    d = np.stack([np.sin(up) * np.cos(around), -np.cos(up), np.sin(up) * np.sin(around)], 1)
    p = _held(rig, W, 80)
    shift = p[:, K["LS"]] + np.linalg.norm(p[0, K["LE"]] - p[0, K["LS"]]) * d - p[:, K["LE"]]
    p[:, K["LE"]] += shift
    p[:, K["LW"]] += shift
    out = retarget(p, 30.0, rig, weights=W, ground=False)
    assert np.abs(_mapped(out, W) - p).max() < 1e-6
    arm = np.arccos(np.clip(np.sum(d[1:] * d[:-1], 1), -1, 1))
    turn = _turns(out)[:, rig.skeleton.index("LeftArm")]
    assert turn.max() < 2 * arm.max()


def test_the_toe_tips_below_the_mapped_toes_stand_on_the_floor(rig):
    # the rig's standing pose held: its toe tips lie below the toe joints the body maps
    _, W = kit21_weights(rig.skeleton)
    p = _held(rig, W, 30)
    tips = rig.positions()[0, :, 1].min()
    depth = p[0, :, 1].min() - tips
    assert depth > 1e-3
    out = retarget(p, 30.0, rig, weights=W)
    assert out.positions()[:, :, 1].min() == pytest.approx(p[..., 1].min(), abs=1e-9)
    # the whole body raised by that depth, nothing else changed
    np.testing.assert_allclose(_mapped(out, W), p + [0.0, depth, 0.0], atol=1e-6)
    np.testing.assert_allclose(_mapped(retarget(p, 30.0, rig, weights=W, ground=False), W),
                               p, atol=1e-6)


def test_hinge_joints_and_bad_input_are_refused(rig):
    _, W = kit21_weights(rig.skeleton)
    p = _mapped(rig, W)
    joints = list(rig.skeleton.joints)
    i = rig.skeleton.index("LeftLeg")
    joints[i] = Joint("LeftLeg", joints[i].parent, joints[i].offset, axes=[[1.0, 0, 0]])
    hinge = Skeleton(joints, root_axes=ZXY)
    m = Motion(hinge, 30.0, np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, hinge.ndof)))
    with pytest.raises(SkeletonError, match="'LeftLeg' has 1 rotation DOF"):
        retarget(p, 30.0, m, weights=W)
    with pytest.raises(MotionlangError, match="sum to 1"):
        retarget(p, 30.0, rig, weights=2 * W)
    with pytest.raises(MotionlangError, match=r"\(T, K, 3\)"):
        retarget(p[0], 30.0, rig, weights=W)


def test_bandai_round_trip(tmp_path):
    """Bandai BVH -> body -> BVH on the Bandai rig -> body, within 1 cm."""
    bandai_takes(["walk_normal_001"], tmp_path)
    rig = read_bvh(tmp_path / "walk_normal_001.bvh")
    name, W = kit21_weights(rig.skeleton)
    assert name == "bandai"
    p = _mapped(rig, W)
    write_bvh(retarget(p, rig.fps, rig, weights=W), tmp_path / "out.bvh")
    back = read_bvh(tmp_path / "out.bvh")
    assert back.skeleton.names == rig.skeleton.names
    assert back.skeleton.file_unit == rig.skeleton.file_unit == 0.01
    assert np.abs(_mapped(back, W) - p).max() < 0.01
    # a motion of another length (a wave) on the Bandai rig: the right arm moves most
    travel = _wave_travel(rig, W, tmp_path / "wave.bvh")
    assert KIT21_NAMES[int(np.argmax(travel))] == "RW"
    assert set(rig.skeleton.names) <= set(read_bvh(tmp_path / "wave.bvh").skeleton.names)


@pytest.mark.parametrize("name", ["cmu-bvh", "cmu-bvh-max"])
def test_a_long_neck_link_still_points_the_head_up(name, tmp_path):
    """CMU BVH rigs put Neck at the shoulders and reach the head through Neck1: their link is
    longer than the body's whole BLN -> BUN segment, so aiming from the rig's offset alone
    started beyond the head and hung it upside down. The head now takes the body's
    direction."""
    from helpers.mocap import synthetic_mmm
    from helpers.rigs import RIGS, write
    src = synthetic_mmm(T=40)                      # MMM proportions: a short neck
    rig = read_motion(write(RIGS[name], tmp_path, T=4))
    out = retarget(positions21(src), src.fps, rig, weights=kit21_weights(rig.skeleton)[1])
    head = out.skeleton.names.index("Head")
    P, p = out.positions(), positions21(src)
    bone = P[:, head] - P[:, out.skeleton.joints[head].parent]
    assert (bone[:, 1] > 0).all(), "the head hangs below its parent"
    assert np.degrees(_angle(bone, p[:, K["BUN"]] - p[:, K["BLN"]])).max() < 15

"""Reading back the skeletal animation of a glTF 2.0 / GLB file: node names, hierarchy,
frame rate and every node's world position at every key.

This is the check on :mod:`motionlang.formats.gltf` (a reader that knows nothing of
motionlang's skeletons: it composes the nodes' translation, rotation and scale as glTF
defines them) and lets a user or a test see what a viewer will show. It reads the first
animation of a file whose channels share one set of key times (as motionlang writes
them); a file that needs interpolation between differing key times is refused, as are
sparse accessors and external buffers. :func:`read_gltf` turns the skeleton's played
positions into a :class:`Motion` (joint angles fitted to them), so that ``info``,
``render``, ``describe`` and ``convert`` take a GLB as they take a BVH.
"""
from __future__ import annotations

import base64
import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.kinematics.from_positions import ZXY, motion_from_positions
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton
from motionlang.utils.limits import check_file, check_motion

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
           5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


@dataclass
class GltfAnimation:
    """What :func:`read_gltf_animation` found.

    Attributes:
        names: node names (J,), in node order.
        parents: (J,) index of each node's parent, -1 for a scene root.
        times: (T,) key times in seconds.
        fps: frames per second, from the key spacing.
        positions: (T, J, 3) world positions in the file's units (metres, Y up).
        rotations: (T, J, 3, 3) world rotation (times scale) of each node.
        skin_joints: the node indices of the first skin (empty without one).
        name: the animation's name.
    """

    names: list[str]
    parents: np.ndarray
    times: np.ndarray
    fps: float
    positions: np.ndarray
    rotations: np.ndarray
    skin_joints: list[int]
    name: str


def _buffers(gltf, path: Path) -> list[bytes]:
    out = []
    for i, buf in enumerate(gltf.buffers):
        uri = buf.uri
        if uri is None:
            data = gltf.binary_blob()
            if data is None:
                raise MotionFormatError(path, f"buffer {i} has no data")
        elif uri.startswith("data:") and ";base64," in uri:
            data = base64.b64decode(uri.split(";base64,", 1)[1])
        else:
            raise MotionFormatError(path, f"buffer {i} is an external file ({uri[:60]}); "
                                          "only GLB or embedded buffers are read")
        out.append(bytes(data))
    return out


def _accessor(gltf, buffers: list[bytes], index: int, path: Path) -> np.ndarray:
    """Accessor ``index`` as an array (count, width) (float32 when normalised)."""
    try:
        acc = gltf.accessors[index]
        if acc.sparse is not None or acc.bufferView is None:
            raise MotionFormatError(path, f"accessor {index}: sparse or empty accessors "
                                          "are not read")
        view = gltf.bufferViews[acc.bufferView]
        dtype = np.dtype(_DTYPES[acc.componentType])
        width = _WIDTH[acc.type]
        data = buffers[view.buffer]
        start = (view.byteOffset or 0) + (acc.byteOffset or 0)
        row = dtype.itemsize * width
        stride = view.byteStride or row
        end = start + stride * (acc.count - 1) + row if acc.count else start
        if min(view.byteOffset or 0, acc.byteOffset or 0, view.byteLength, acc.count) < 0:
            raise MotionFormatError(path, f"accessor {index} (bufferView {acc.bufferView}): "
                                          "a negative offset, length or count")
        past = stride < row or end > (view.byteOffset or 0) + \
            view.byteLength or end > len(data)
    except (IndexError, KeyError, TypeError) as exc:   # TypeError: a field that is null
        raise MotionFormatError(path, f"accessor {index} is malformed ({exc})") from None
    if past:
        raise MotionFormatError(path, f"accessor {index} runs past its buffer")
    raw = np.frombuffer(data, np.uint8, count=end - start, offset=start)
    if stride != row:
        raw = np.lib.stride_tricks.as_strided(raw, (acc.count, row), (stride, 1))
    return np.frombuffer(np.ascontiguousarray(raw).tobytes(), dtype).reshape(acc.count, width)


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) in (x, y, z, w) order -> rotation matrices (..., 3, 3)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_quat(q.reshape(-1, 4)).as_matrix().reshape(q.shape[:-1] + (3, 3))


def read_gltf_animation(path: str | Path, animation: int = 0) -> GltfAnimation:
    """Read ``path`` (``.glb`` or ``.gltf``) and play its ``animation``: every node's world
    position at every key time (module docstring for what is refused).

    Raises:
        MotionFormatError: a missing, malformed or unsupported file, naming it.
    """
    path = Path(path)
    try:
        import pygltflib
    except ImportError:   # an optional dependency: the export extra
        raise MotionFormatError(path, "reading glTF needs pygltflib: pip install "
                                      "'motionlang[export]'") from None
    check_file(path, parse_factor=3.0)
    try:
        gltf = pygltflib.GLTF2.load(str(path))
    except Exception as exc:   # pygltflib raises whatever its JSON and struct parsing hit
        raise MotionFormatError(path, f"not a readable glTF file ({type(exc).__name__}: "
                                      f"{str(exc)[:80]})") from None
    if gltf is None or not gltf.nodes:
        raise MotionFormatError(path, "no nodes")
    if not 0 <= animation < len(gltf.animations):
        raise MotionFormatError(path, f"no animation {animation} (the file has "
                                      f"{len(gltf.animations)})")
    buffers = _buffers(gltf, path)
    J = len(gltf.nodes)
    parents = np.full(J, -1)
    for i, node in enumerate(gltf.nodes):
        for c in node.children or []:
            if not 0 <= c < J or parents[c] >= 0 or c == i:
                raise MotionFormatError(path, f"node {i}: bad child {c}")
            parents[c] = i
    order = _topological(parents, path)
    anim = gltf.animations[animation]
    times = None
    tracks: dict[tuple[int, str], np.ndarray] = {}
    for ch in anim.channels or []:
        try:   # a null sampler, target or index
            sampler = anim.samplers[ch.sampler]
            node, what = int(ch.target.node), str(ch.target.path)
        except (AttributeError, IndexError, TypeError) as exc:
            raise MotionFormatError(path, f"an animation channel is malformed ({exc})"
                                    ) from None
        t = _accessor(gltf, buffers, sampler.input, path)[:, 0].astype(float)
        if times is None:
            times = t
        elif len(t) != len(times) or np.abs(t - times).max() > 1e-6:
            raise MotionFormatError(path, "animation channels have different key times")
        values = _accessor(gltf, buffers, sampler.output, path).astype(float)
        width = 4 if what == "rotation" else 3
        if values.shape != (len(t), width):
            raise MotionFormatError(path, f"{what} of node {node}: {values.shape} values for "
                                          f"{len(t)} keys of {width}")
        tracks[(node, what)] = values
    if times is None or not len(times):
        raise MotionFormatError(path, f"animation {animation} has no keys")
    T = len(times)
    check_motion(path, T, J)
    trans = np.empty((T, J, 3))
    rots = np.empty((T, J, 3, 3))
    scale = np.empty((T, J, 3))
    for j, node in enumerate(gltf.nodes):
        if node.matrix is not None and tracks.keys() & {(j, "translation"), (j, "rotation")}:
            raise MotionFormatError(path, f"node {j}: an animated node with a matrix")
        trans[:, j] = tracks.get((j, "translation"), np.asarray(node.translation or [0, 0, 0]))
        q = tracks.get((j, "rotation"), np.asarray(node.rotation or [0, 0, 0, 1.0]))
        norm = np.linalg.norm(np.broadcast_to(q, (T, 4)), axis=-1)
        if not np.all(np.isfinite(norm) & (norm > 1e-6)):   # glTF's are unit quaternions
            raise MotionFormatError(path, f"node {j}: a rotation that is no unit quaternion")
        rots[:, j] = _quat_matrix(np.broadcast_to(q, (T, 4)))
        scale[:, j] = tracks.get((j, "scale"), np.asarray(node.scale or [1, 1, 1.0]))
    world_R = np.empty((T, J, 3, 3))
    world_t = np.empty((T, J, 3))
    for j in order:
        local = rots[:, j] * scale[:, j, None, :]
        p = parents[j]
        if p < 0:
            world_R[:, j], world_t[:, j] = local, trans[:, j]
        else:
            world_R[:, j] = world_R[:, p] @ local
            world_t[:, j] = world_t[:, p] + np.einsum("tij,tj->ti", world_R[:, p], trans[:, j])
    step = float(np.median(np.diff(times))) if T > 1 else 0.0
    given = (anim.extras or {}).get("fps") if isinstance(anim.extras, dict) else None
    if given is not None and (isinstance(given, bool) or not isinstance(given, (int, float))
                              or not math.isfinite(given) or given <= 0):
        raise MotionFormatError(path, f"animation {animation}: extras.fps must be a positive "
                                      f"number, got {str(given)[:40]!r}")
    fps = float(given or (1.0 / step if step > 0 else 0.0))
    skins = gltf.skins[0].joints if gltf.skins else []
    return GltfAnimation(names=[n.name or f"node{i}" for i, n in enumerate(gltf.nodes)],
                         parents=parents, times=times, fps=fps, positions=world_t,
                         rotations=world_R,
                         skin_joints=list(skins), name=anim.name or "")


def _topological(parents: np.ndarray, path: Path) -> list[int]:
    """Nodes with every parent before its children (refusing cycles)."""
    children: dict[int, list[int]] = {}
    for j, p in enumerate(parents):
        children.setdefault(int(p), []).append(j)
    order, stack = [], list(reversed(children.get(-1, [])))
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(children.get(j, [])))
    if len(order) != len(parents):
        raise MotionFormatError(path, "the node hierarchy has a cycle")
    return order


def read_gltf(path: str | Path) -> Motion:
    """A glTF / GLB file's skeletal animation as a :class:`Motion` on the joints of its first
    skin (all nodes without one), in metres, Y up, as glTF is. Where every joint keeps its
    offset from its parent and no node is scaled (a rig, as motionlang and Blender write
    them), the joints' own rotations are read exactly; otherwise joint angles are fitted to
    the played positions (``kinematics.from_positions``).

    Raises:
        MotionFormatError: as :func:`read_gltf_animation`, or joints that are not one tree,
            or no frame rate.
    """
    path = Path(path)
    anim = read_gltf_animation(path)
    chosen = set(anim.skin_joints) if anim.skin_joints else set(range(len(anim.names)))
    order = [j for j in _topological(anim.parents, path) if j in chosen]

    def kept_parent(j: int) -> int:
        p = int(anim.parents[j])
        while p >= 0 and p not in chosen:
            p = int(anim.parents[p])
        return p

    index = {j: i for i, j in enumerate(order)}
    parents = [index.get(kept_parent(j), -1) for j in order]
    roots = sum(p < 0 for p in parents)
    if not order or roots != 1:
        raise MotionFormatError(path, f"its joints are not one tree ({roots} roots)")
    if not anim.fps > 0:
        raise MotionFormatError(path, "a single key and no frame rate (extras.fps)")
    names = [anim.names[j] for j in order]
    R, x = anim.rotations[:, order], anim.positions[:, order]
    motion = _rig_motion(R, x, anim.fps, names, parents, anim.name or path.stem)
    if motion is None:
        motion = motion_from_positions(x, anim.fps, names, parents, name=anim.name or path.stem)
    return dataclasses.replace(motion, source_format="gltf")


def _rig_motion(R: np.ndarray, x: np.ndarray, fps: float, names: list[str],
                parents: list[int], name: str) -> Motion | None:
    """The Motion whose joints turn as the nodes' world rotations R (T, J, 3, 3) say, at
    the world positions x (T, J, 3); None where a node is scaled or a joint's offset from
    its parent changes over time (no rig with fixed bones plays it)."""
    T = len(R)
    eye = np.eye(3)
    if np.abs(np.swapaxes(R, -1, -2) @ R - eye).max() > 1e-4:   # scaled or sheared
        return None
    joints = [Joint(names[0], -1, np.zeros(3))]   # its turn: root_rotation
    angles = []
    has_kids = {q for q in parents if q >= 0}
    for j in range(1, len(names)):
        q = parents[j]
        offset = np.einsum("tji,tj->ti", R[:, q], x[:, j] - x[:, q])   # in the parent's frame
        if np.abs(offset - offset[0]).max() > 1e-4 * max(1.0, float(np.abs(offset).max())):
            return None
        local = np.swapaxes(R[:, q], -1, -2) @ R[:, j]
        if j in has_kids:
            joints.append(Joint(names[j], q, offset[0], axes=ZXY,
                                dof_names=tuple(f"{names[j]}_{c}rotation" for c in "ZXY")))
            angles.append(np.unwrap(matrix_to_chain(local, ZXY), axis=0))
        else:   # a leaf's turn moves no joint
            joints.append(Joint(names[j], q, offset[0]))
    sk = Skeleton(joints, root_axes=ZXY, name=name)
    joint_angles = np.concatenate(angles, axis=1) if angles else np.zeros((T, 0))
    root_rotation = np.unwrap(matrix_to_chain(R[:, 0], ZXY), axis=0)
    return Motion(sk, float(fps), x[:, 0].copy(), root_rotation, joint_angles, name=name)

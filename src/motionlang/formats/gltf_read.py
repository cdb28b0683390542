"""Reading back the skeletal animation of a glTF 2.0 / GLB file: node names, hierarchy,
frame rate and every node's world position at every key.

This is the check on :mod:`motionlang.formats.gltf` (a reader that knows nothing of
motionlang's skeletons: it composes the nodes' translation, rotation and scale as glTF
defines them) and lets a user or a test see what a viewer will show. It reads the first
animation of a file whose channels share one set of key times (as motionlang writes
them); a file that needs interpolation between differing key times is refused, as are
sparse accessors and external buffers.
"""
from __future__ import annotations

import base64
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
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
        skin_joints: the node indices of the first skin (empty without one).
        name: the animation's name.
    """

    names: list[str]
    parents: np.ndarray
    times: np.ndarray
    fps: float
    positions: np.ndarray
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
        past = acc.count < 0 or stride < row or end > (view.byteOffset or 0) + \
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
    import pygltflib

    path = Path(path)
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
    fps = float((anim.extras or {}).get("fps") or (1.0 / step if step > 0 else 0.0))
    skins = gltf.skins[0].joints if gltf.skins else []
    return GltfAnimation(names=[n.name or f"node{i}" for i, n in enumerate(gltf.nodes)],
                         parents=parents, times=times, fps=fps, positions=world_t,
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

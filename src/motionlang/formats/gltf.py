"""Writing glTF 2.0 (``.gltf``) and GLB (``.glb``): a Motion as a skinned, animated skeleton.

What a file holds:

* one node per skeleton joint (End Sites and fixed segments included), named as the joint
  and parented as in the skeleton, in skeleton order: node ``j`` is joint ``j``;
* a skin over all of them, so that Blender, Unity, Unreal, Godot and the web viewers make
  an armature of it, and a small skinned mesh (a thin eight-faced spindle along each bone,
  bound to the bone's parent joint) so that a viewer shows a figure without a character;
* one animation named after the motion: the root's translation and every joint's local
  rotation that moves, one key per frame at ``t = frame / fps`` seconds (LINEAR), so the
  keys are the frames and a reader finds the frame rate from their spacing
  (``extras["fps"]`` says it too).

Units and axes. glTF lengths are metres and its frame is Y up; motionlang's canonical
frame is the same (``Motion.positions``), so lengths are written in metres whatever the
source unit (the user's rig keeps its proportions and rest pose, not its file unit), and
the source frame is turned into the canonical one at the root: the root's translation and
rotation get ``skeleton.world``, every other joint keeps its local rotation relative to its
parent, which that turn does not change. The body faces where the source had it face
(glTF's +Z "front" is not imposed). Rest pose (the nodes' own transforms and the skin's
bind pose): every DOF at zero with the root at its first-frame position; for a BVH that is
the file's own rest pose (its OFFSETs), for a retargeted motion the user's rig's.
"""
from __future__ import annotations

import base64
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.kinematics.motion import Motion
from motionlang.utils.atomic import atomic_path

GLTF_EXTENSIONS = (".glb", ".gltf")
#: glTF component types and accessor kinds used here (glTF 2.0 spec, "Accessors")
_FLOAT, _USHORT = 5126, 5123
_ARRAY, _ELEMENTS = 34962, 34963


def _quat_xyzw(R: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) -> unit quaternions (..., 4) in glTF's (x, y, z, w)
    order; consecutive rows along axis 0 are sign-aligned so that interpolating between
    two keys takes the short way."""
    from scipy.spatial.transform import Rotation

    flat = R.reshape(-1, 3, 3)
    q = Rotation.from_matrix(flat).as_quat().reshape(R.shape[:-2] + (4,))
    if q.ndim == 2 and len(q) > 1:
        flip = np.cumprod(np.where(np.sum(q[1:] * q[:-1], axis=-1) < 0, -1.0, 1.0))
        q[1:] *= flip[:, None]
    return q


def local_transforms(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """The per-frame transforms a glTF node holds, in glTF's frame (Y up, metres).

    Returns:
        root translation (T, 3) metres (the root joint's world position) and local
        rotations (T, J, 3, 3): the root's relative to the world, every other joint's
        relative to its parent joint.
    """
    rots, pos = motion.global_transforms()
    W = motion.skeleton.world
    parents = motion.skeleton.parents
    local = np.empty_like(rots)
    for j, p in enumerate(parents):
        local[:, j] = W @ rots[:, j] if p < 0 else np.swapaxes(rots[:, p], -1, -2) @ rots[:, j]
    return pos[:, 0] @ W.T, local


def rest_motion(motion: Motion) -> Motion:
    """One frame: every DOF and the root rotation at zero, the root where it starts."""
    return motion.replace(root_translation=motion.root_translation[:1],
                          root_rotation=np.zeros_like(motion.root_rotation[:1]),
                          joint_angles=np.zeros_like(motion.joint_angles[:1]))


def _spindles(heads: np.ndarray, parents: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A thin eight-faced spindle from each joint's parent to the joint (rest positions
    ``heads`` (J, 3) metres), bound to the parent. Returns vertices (V, 3) float32,
    triangle indices (F*3,) uint16/uint32 and the joint of each vertex (V,) uint16."""
    verts, faces, owner = [], [], []
    for j, p in enumerate(parents):
        if p < 0:
            continue
        a, b = heads[p], heads[j]
        d = b - a
        length = float(np.linalg.norm(d))
        if length < 1e-6:
            continue
        axis = d / length
        helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
        u = np.cross(axis, helper)
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        w = float(np.clip(0.08 * length, 0.004, 0.025))
        mid = a + 0.2 * d
        ring = [mid + w * u, mid + w * v, mid - w * u, mid - w * v]
        base = len(verts)
        verts += [a, *ring, b]
        for k in range(4):
            r0, r1 = base + 1 + k, base + 1 + (k + 1) % 4
            faces += [(base, r1, r0), (base + 5, r0, r1)]
        owner += [p] * 6
    return (np.asarray(verts, np.float32).reshape(-1, 3),
            np.asarray(faces, np.uint32).reshape(-1), np.asarray(owner, np.uint16))


class _Blob:
    """The one binary buffer and the accessors pointing into it."""

    def __init__(self, gltf):
        self.gltf, self.data = gltf, bytearray()

    def add(self, array: np.ndarray, kind: str, component: int, target: int | None = None,
            bounds: bool = False) -> int:
        import pygltflib

        array = np.ascontiguousarray(array)
        self.data += b"\0" * (-len(self.data) % 4)   # glTF: accessors 4-byte aligned
        view = pygltflib.BufferView(buffer=0, byteOffset=len(self.data),
                                    byteLength=array.nbytes, target=target)
        self.data += array.tobytes()
        self.gltf.bufferViews.append(view)
        flat = array.reshape(len(array), -1)
        acc = pygltflib.Accessor(bufferView=len(self.gltf.bufferViews) - 1,
                                 componentType=component, count=len(array), type=kind)
        if bounds:   # required for POSITION and animation inputs
            acc.min = [float(x) for x in flat.min(axis=0)]
            acc.max = [float(x) for x in flat.max(axis=0)]
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1


def _mat4(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(N, 4, 4) rigid transforms from rotations (N, 3, 3) and translations (N, 3)."""
    M = np.zeros((len(R), 4, 4))
    M[:, :3, :3], M[:, :3, 3], M[:, 3, 3] = R, t, 1.0
    return M


def _column_major(M: np.ndarray) -> np.ndarray:
    """(N, 4, 4) -> (N, 16) float32 as glTF stores a MAT4 (column by column)."""
    return np.swapaxes(M, -1, -2).reshape(len(M), 16).astype(np.float32)


def gltf_document(motion: Motion, *, mesh: bool = True):
    """``motion`` as a ``pygltflib.GLTF2`` (module docstring) and its binary buffer."""
    import pygltflib

    sk = motion.skeleton
    J, T = len(sk), motion.n_frames
    parents = sk.parents
    rest = rest_motion(motion)
    rest_root, rest_local = local_transforms(rest)
    rest_rots, rest_pos = rest.global_transforms()
    rest_rots = sk.world @ rest_rots[0]
    rest_pos = rest_pos[0] @ sk.world.T
    root_t, local = local_transforms(motion)
    gltf = pygltflib.GLTF2(asset=pygltflib.Asset(generator="motionlang", version="2.0"))
    blob = _Blob(gltf)
    rest_q = _quat_xyzw(rest_local[0])
    for j, joint in enumerate(sk.joints):
        t = rest_root[0] if parents[j] < 0 else joint.offset
        gltf.nodes.append(pygltflib.Node(
            name=joint.name, translation=[float(x) for x in t],
            rotation=[float(x) for x in rest_q[j]],
            children=[int(c) for c in np.flatnonzero(parents == j)]))
    ibm = blob.add(_column_major(np.linalg.inv(_mat4(rest_rots, rest_pos))), "MAT4", _FLOAT)
    gltf.skins.append(pygltflib.Skin(name=sk.name, joints=list(range(J)), skeleton=0,
                                     inverseBindMatrices=ibm))
    scene_nodes = [0]
    verts, faces, owner = _spindles(rest_pos, parents) if mesh else (np.zeros((0, 3)),) * 3
    if len(verts):
        joints4 = np.zeros((len(verts), 4), np.uint16)
        joints4[:, 0] = owner
        weights4 = np.zeros((len(verts), 4), np.float32)
        weights4[:, 0] = 1.0
        index_type = np.uint16 if len(verts) < 65535 else np.uint32
        attrs = pygltflib.Attributes(
            POSITION=blob.add(verts, "VEC3", _FLOAT, _ARRAY, bounds=True),
            JOINTS_0=blob.add(joints4, "VEC4", _USHORT, _ARRAY),
            WEIGHTS_0=blob.add(weights4, "VEC4", _FLOAT, _ARRAY))
        indices = blob.add(faces.astype(index_type), "SCALAR",
                           _USHORT if index_type is np.uint16 else 5125, _ELEMENTS)
        gltf.meshes.append(pygltflib.Mesh(name=f"{sk.name} bones", primitives=[
            pygltflib.Primitive(attributes=attrs, indices=indices)]))
        gltf.nodes.append(pygltflib.Node(name=f"{motion.name} mesh", mesh=0, skin=0))
        scene_nodes.append(len(gltf.nodes) - 1)
    gltf.scenes.append(pygltflib.Scene(name=motion.name, nodes=scene_nodes))
    gltf.scene = 0

    times = blob.add((np.arange(T) / motion.fps).astype(np.float32), "SCALAR", _FLOAT,
                     bounds=True)
    samplers, channels = [], []

    def animate(node: int, path: str, values: np.ndarray, kind: str) -> None:
        samplers.append(pygltflib.AnimationSampler(
            input=times, output=blob.add(values.astype(np.float32), kind, _FLOAT),
            interpolation="LINEAR"))
        channels.append(pygltflib.AnimationChannel(
            sampler=len(samplers) - 1,
            target=pygltflib.AnimationChannelTarget(node=node, path=path)))

    animate(0, "translation", root_t, "VEC3")
    for j in range(J):
        q = _quat_xyzw(local[:, j])
        if j == 0 or np.abs(np.abs(q @ rest_q[j]) - 1.0).max() > 1e-12:
            animate(j, "rotation", q, "VEC4")
    gltf.animations.append(pygltflib.Animation(
        name=motion.name, samplers=samplers, channels=channels,
        extras={"fps": float(motion.fps), "frames": T}))
    gltf.buffers.append(pygltflib.Buffer(byteLength=len(blob.data)))
    return gltf, bytes(blob.data)


def write_gltf(motion: Motion, path: str | Path, *, mesh: bool = True) -> Path:
    """Write ``motion`` as ``.glb`` (one binary file) or ``.gltf`` (JSON with the buffer
    inside as a base64 data URI, so it is one file too); atomic. ``mesh=False`` leaves out
    the spindle mesh (the skin and the armature stay). Returns the path.

    Raises:
        MotionFormatError: another extension, or pygltflib not installed.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in GLTF_EXTENSIONS:
        raise MotionFormatError(path, f"not a glTF file name: use {' or '.join(GLTF_EXTENSIONS)}")
    try:
        import pygltflib  # noqa: F401
    except ImportError:
        raise MotionFormatError(path, "writing glTF needs pygltflib: pip install "
                                      "'motionlang[export]'") from None

    gltf, data = gltf_document(motion, mesh=mesh)
    if ext == ".glb":
        gltf.set_binary_blob(data)
    else:
        gltf.buffers[0].uri = "data:application/octet-stream;base64," + \
            base64.b64encode(data).decode("ascii")
    with atomic_path(path) as tmp:
        if ext == ".glb":
            gltf.save_binary(str(tmp))
        else:
            gltf.save_json(str(tmp))
    return path

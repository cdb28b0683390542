"""Joint positions -> a ``Motion`` with joint angles, so that position-only output (the
two-stream model's 21 joints) can be written as BVH and taken into Blender.

The skeleton has one node per given joint, BVH-style (``pre = post = I``, ``Z X Y`` Euler
channels, world = canonical Y-up frame). A node's offset is its bone (parent -> node) in
the rest pose, scaled to the bone's median length over the motion: positions predicted by
a network do not keep bone lengths, a skeleton must. Each frame, every node's global
rotation G is chosen so that it carries its children's rest bones onto their current ones:

* one child: the smallest rotation, relative to the parent's frame, that turns the rest
  bone into the current bone, starting from the node's rotation relative to its parent in
  the frame before (its twist about the bone is not in the positions; carried over from
  frame to frame it changes smoothly, even where the bone turns half round from its rest
  direction, an arm raised overhead from arms down);
* several children (pelvis: lumbar + hips; neck: head + shoulders): the least-squares
  rotation of all of them (Kabsch), which fixes the twist too — unless in some frame the
  children lie on one line through the node; that frame is treated as one-child (its
  first child).

Bones from one-child nodes point exactly where the given ones do; bones from several-child
nodes are off where the given body is not rigid (a few degrees on generated motions); all
lengths become constant. :func:`position_error` gives the resulting joint errors (metres;
about 1 cm on average on the two-stream model's motions, zero on positions of a rigid
skeleton).
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton

#: BVH's usual Euler order, as intrinsic DOF axes (z, then x, then y)
ZXY = np.eye(3)[[2, 0, 1]]
_EPS = 1e-9


def _check(positions: np.ndarray, names: Sequence[str], parents: Sequence[int]) -> np.ndarray:
    p = np.asarray(positions, dtype=float)
    if p.ndim != 3 or p.shape[-1] != 3 or len(p) == 0 or p.shape[1] == 0:
        raise MotionlangError(f"positions must be (T, J, 3) with T, J >= 1, got {p.shape}")
    if not (len(names) == len(parents) == p.shape[1]):
        raise MotionlangError(f"{p.shape[1]} joints in the positions, {len(names)} names and "
                              f"{len(parents)} parents")
    if parents[0] != -1 or any(not 0 <= q < i for i, q in enumerate(parents) if i):
        raise MotionlangError("parents must list the root (-1) first and every parent before "
                              "its child")
    if not np.isfinite(p).all():
        frame, joint = (int(i) for i in np.argwhere(~np.isfinite(p))[0][:2])
        raise MotionlangError(f"positions: non-finite value at frame {frame}, joint "
                              f"{names[joint]!r}")
    return p


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 3) -> unit vectors and a mask of those too short to have a direction."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, _EPS), n[..., 0] > _EPS


def _swing(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Smallest rotations taking unit vectors u to v; (T, 3), (T, 3) -> (T, 3, 3)."""
    c = np.sum(u * v, axis=-1)
    w = np.cross(u, v)
    K = np.zeros(u.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    # Rodrigues with sin and (1 - cos) folded in: R = I + K + K^2 / (1 + c), for c > -1
    R = np.eye(3) + K + (K @ K) / np.maximum(1.0 + c, _EPS)[..., None, None]
    flip = c < -1.0 + 1e-9
    if flip.any():   # opposite vectors: half a turn about any axis across u
        a = np.cross(u[flip], np.array([1.0, 0.0, 0.0]))
        small = np.linalg.norm(a, axis=-1) < 1e-6
        a[small] = np.cross(u[flip][small], np.array([0.0, 1.0, 0.0]))
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        R[flip] = 2.0 * a[:, :, None] * a[:, None, :] - np.eye(3)
    return R


def _kabsch(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotations R minimising sum_i |R a_i - b_i|^2; a (k, 3) rest, b (T, k, 3) -> (T, 3, 3),
    and a (T,) mask of frames where that fixes R (the b_i not all on one line)."""
    H = np.einsum("ki,tkj->tij", a, b)            # sum_i a_i b_i^T
    U, S, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    D = np.broadcast_to(np.eye(3), H.shape).copy()
    D[:, 2, 2] = d
    return np.swapaxes(Vt, -1, -2) @ D @ np.swapaxes(U, -1, -2), S[:, 1] > 1e-3 * S[:, 0]


def _follow(base: np.ndarray, fixed: np.ndarray, fixed_ok: np.ndarray, rest_bone: np.ndarray,
            bone: np.ndarray) -> np.ndarray:
    """Global rotations (T, 3, 3) of a node from its parent's ``base`` (T, 3, 3): ``fixed``
    where ``fixed_ok`` (T,), elsewhere the last frame's rotation relative to the parent
    turned by the smallest rotation that carries ``rest_bone`` (3,) onto ``bone`` (T, 3)."""
    v, has_length = _unit(bone)
    out = np.empty_like(base)
    local = np.eye(3)
    for t in range(len(base)):
        G = fixed[t] if fixed_ok[t] else base[t] @ local
        if not fixed_ok[t] and has_length[t]:   # a bone of zero length keeps the last turn
            u, _ = _unit(G @ rest_bone)
            G = _swing(u[None], v[t][None])[0] @ G
        out[t] = G
        local = base[t].T @ G
    return out


def skeleton_from_positions(positions: np.ndarray, names: Sequence[str],
                            parents: Sequence[int], rest: np.ndarray | None = None,
                            name: str = "positions") -> Skeleton:
    """A BVH-style skeleton for ``positions`` (T, J, 3) metres, Y up.

    Offsets: the bone directions of ``rest`` (J, 3) (default: each bone's first frame with
    a length) times each bone's median length over the T frames. Nodes with children get ``Z X Y`` rotation
    DOFs, leaves none (BVH End Sites).
    """
    p = _check(positions, names, parents)
    if rest is not None:
        rest = np.asarray(rest, dtype=float)
        if rest.shape != p.shape[1:] or not np.isfinite(rest).all():
            raise MotionlangError(f"rest pose must be {p.shape[1:]} finite numbers, got "
                                  f"{rest.shape}")
    joints = [Joint(names[0], -1, np.zeros(3))]
    has_kids = {q for q in parents if q >= 0}
    for j in range(1, len(names)):
        q = parents[j]
        bones = p[:, j] - p[:, q]
        lengths = np.linalg.norm(bones, axis=-1)
        length = float(np.median(lengths))
        if rest is not None:
            direction, ok = _unit(rest[j] - rest[q])
            if not ok:
                raise MotionlangError(f"rest pose: joint {names[j]!r} sits on its parent "
                                      f"{names[q]!r}, its bone has no direction")
        else:   # the first frame in which the bone has a direction
            if not (lengths > _EPS).any():
                raise MotionlangError(f"positions: joint {names[j]!r} sits on its parent "
                                      f"{names[q]!r} in every frame")
            direction, _ = _unit(bones[int(np.argmax(lengths > _EPS))])
        axes = ZXY if j in has_kids else np.zeros((0, 3))
        dofs = tuple(f"{names[j]}_{c}rotation" for c in "ZXY") if j in has_kids else ()
        joints.append(Joint(names[j], q, direction * length, axes=axes, dof_names=dofs))
    return Skeleton(joints, root_axes=ZXY, name=name)


def motion_from_positions(positions: np.ndarray, fps: float, names: Sequence[str],
                          parents: Sequence[int], *, rest: np.ndarray | None = None,
                          name: str = "positions") -> Motion:
    """Joint angles that fit ``positions`` (T, J, 3) metres (canonical frame, Y up, joint 0
    the root) at ``fps`` Hz on :func:`skeleton_from_positions`' skeleton (see the module
    docstring for how, and what comes out exact).

    Angles are radians, unwrapped over time (no 360-degree jumps in the BVH curves).
    """
    p = _check(positions, names, parents)
    sk = skeleton_from_positions(p, names, parents, rest=rest, name=name)
    T, J = p.shape[:2]
    kids = [sk.children(j) for j in range(J)]
    G = np.broadcast_to(np.eye(3), (T, J, 3, 3)).copy()   # global rotation of each node
    for j in range(J):
        base = G[:, parents[j]] if j else G[:, 0]          # the root's "parent": the world
        if not kids[j]:
            G[:, j] = base
            continue
        rest_bones = np.stack([sk.joints[c].offset for c in kids[j]])     # (k, 3)
        bones = p[:, kids[j]] - p[:, j, None]                              # (T, k, 3)
        fixed, fixed_ok = _kabsch(rest_bones, bones) if len(kids[j]) >= 2 else \
            (G[:, j], np.zeros(T, dtype=bool))
        if fixed_ok.all():
            G[:, j] = fixed
        else:
            G[:, j] = _follow(base, fixed, fixed_ok, rest_bones[0], bones[:, 0])
    local = np.swapaxes(G[:, parents[1:]], -1, -2) @ G[:, 1:]             # (T, J-1, 3, 3)
    angles = [np.unwrap(matrix_to_chain(local[:, j - 1], ZXY), axis=0)
              for j in range(1, J) if sk.joints[j].ndof]
    joint_angles = np.concatenate(angles, axis=1) if angles else np.zeros((T, 0))
    root_rotation = np.unwrap(matrix_to_chain(G[:, 0], ZXY), axis=0)
    return Motion(sk, float(fps), p[:, 0].copy(), root_rotation, joint_angles, name=name,
                  source_format="positions")


def position_error(motion: Motion, positions: np.ndarray) -> np.ndarray:
    """(T, J) metres between ``motion``'s joints and the ``positions`` it was made from."""
    return np.linalg.norm(motion.positions() - np.asarray(positions, dtype=float), axis=-1)


def _partners(skeleton: Skeleton) -> list[int]:
    """Each joint's left/right partner (itself on the midline): ``skeleton.pairs``, and
    joints named after a paired one (``Hand_L_end`` goes with ``Hand_R_end``)."""
    names = skeleton.names
    index = {n: i for i, n in enumerate(names)}
    out = list(range(len(names)))
    for a, b in skeleton.pairs:
        for n in names:
            for x, y in ((a, b), (b, a)):
                if n.startswith(x) and n.replace(x, y, 1) in index:
                    out[index[n]] = index[n.replace(x, y, 1)]
    return out


def mirror_motion(motion: Motion, tol: float = 0.05) -> Motion:
    """``motion`` with left and right swapped, on any rig.

    ``Motion.mirror`` (same skeleton) where it holds on this rig: on frame 0 the median
    joint must land within ``tol`` metres of its reflected partner (the median, since real
    rigs are not quite symmetric: CMU subject 35's median joint is 2 cm off, MMM's 0). Rigs
    whose rest pose is not mirror-symmetric in the parent frames (Bandai Namco's lays every
    bone along its local x axis, so ``R' = S R S`` folds the spine down) fail that, and get
    the mirror by positions instead: the reflected, partner-swapped joint positions fitted
    by :func:`motion_from_positions` on the same joint names (bone lengths kept, so exact
    to rounding; joints at zero distance from their parent dropped).
    """
    sk = motion.skeleton
    S = sk.world @ sk.mirror @ sk.world.T   # the source frame's reflection, canonical frame
    partner = _partners(sk)
    first = motion[:1]
    try:
        miss = first.mirror().positions() - first.positions()[:, partner] @ S
        if np.median(np.linalg.norm(miss[0], axis=-1)) <= tol:
            return motion.mirror()
    except MotionlangError:   # SkeletonError: not symmetric in Motion.mirror's sense
        pass
    keep = [0] + [j for j in range(1, len(sk.joints))
                  if np.linalg.norm(sk.joints[j].offset) > _EPS]
    new = {j: i for i, j in enumerate(keep)}

    def kept_parent(j: int) -> int:   # a dropped joint's children hang from its parent
        q = sk.joints[j].parent
        return new[q] if q in new else kept_parent(q)
    parents = [-1] + [kept_parent(j) for j in keep[1:]]
    p = (motion.positions()[:, partner] @ S)[:, keep]
    out = motion_from_positions(p, motion.fps, [sk.names[j] for j in keep], parents,
                                name=sk.name)
    out.meta = {**motion.meta, "mirrored": not motion.meta.get("mirrored", False)}
    return out

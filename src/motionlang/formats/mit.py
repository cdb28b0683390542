"""MIT walking data (Hsu, Pulli & Popovic 2005) as Graham Taylor distributed it with his CRBM
code: ``motion.mat`` holding ``skel`` (an 18-node tree) and ``Motion`` (1 x N cell of
(T, 108) arrays at 30 Hz).

Layout, worked out from the data itself (no documentation came with it; the tests in
``tests/test_mit.py`` check the resulting walker):

* ``skel.tree(i)`` has ``parent`` (1-based, empty for the root), ``children``, ``or`` and
  ``offset``: the 1-based columns of the node's 3 rotation channels and 3 offset channels.
  Every node has both, so 18 x 6 = 108 columns.
* Offsets are in mm, in the parent's frame, and constant for every node but the root,
  whose offset channels are its position (Z up; X is the walking direction, Y the
  subject's left). The root hardly travels: the subject walks on the spot (treadmill-like),
  the stance foot sliding backwards at about 1 m/s.
* Rotations are intrinsic X-Y-Z Euler angles in radians, ``R = Rx(a) Ry(b) Rz(c)`` with
  ``(a, b, c)`` the node's 3 channels, composed child-after-parent (``W = W_parent @ R``).
  Knees have only a Y (lateral) channel; positive flexes the knee. (Angles are small, so
  Y-Z-X, Y-X-Z or an exponential map fit the data almost as well; X-Y-Z fits best.)
* The root is different: its angles ``(a, b, c)`` (about pi/2, pi/2, 0 when standing)
  give the pelvis frame ``Q @ Rx(a) @ Rz(c) @ Ry(b) @ Q``, ``Q`` the cyclic axis permutation
  x->y->z->x (``Q @ Rx(pi/2) @ Ry(pi/2) @ Q = I``). Nothing in the file says so; of the 7
  rotation conventions x 24 x 24 fixed axis permutations tried, this one leaves the foot on
  the ground sliding least sideways (median 6 mm/frame against 16 for a plain X-Y-Z chain,
  at 35 mm/frame backwards) and keeps three distinct axes (b is pelvic obliquity about the
  walking direction, c its rotation about the vertical, a a slow tilt). The reader stores
  the root as yaw-pitch-roll about Z, Y, X of the Z-up frame (``root_axes = [z, y, x]``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import chain, matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton

MIT_FPS = 30.0
#: names of the 18 nodes of Taylor's MIT tree, in file order (node positions: the joint
#: each node rotates about; "toes"/"hand" nodes are end points whose rotation moves nothing).
MIT_JOINT_NAMES = (
    "pelvis", "lhip", "lknee", "lankle", "ltoes", "rhip", "rknee", "rankle", "rtoes",
    "thorax", "lclavicle", "lshoulder", "lelbow", "lwrist",
    "rclavicle", "rshoulder", "relbow", "rwrist",
)
#: parent index of each node of the standard tree (to recognise it; others get generic names)
MIT_PARENTS = (-1, 0, 1, 2, 3, 0, 5, 6, 7, 0, 9, 10, 11, 12, 9, 14, 15, 16)
#: Z-up source frame (X forward, Y left) -> canonical (Y up, Z forward, X left).
MIT_WORLD = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
#: cyclic axis permutation x->y->z->x (see module docstring for the root convention)
Q_CYCLE = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: the root's chain: X, then Z, then Y, taking channels (a, c, b)
ROOT_FILE_AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
ROOT_AXES = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
XYZ = np.eye(3)


def root_matrix(channels: np.ndarray) -> np.ndarray:
    """(..., 3) root channels (a, b, c) of the file -> (..., 3, 3) pelvis frame (Z up)."""
    channels = np.asarray(channels, dtype=float)
    return Q_CYCLE @ chain(ROOT_FILE_AXES, channels[..., [0, 2, 1]]) @ Q_CYCLE


def _field(struct, name: str, path) -> np.ndarray:
    try:
        return np.asarray(struct[name]).squeeze()
    except (KeyError, ValueError, IndexError):
        raise MotionFormatError(path, f"MIT skeleton node has no {name!r} field") from None


def _columns(node, name: str, ncols: int, path, i: int) -> np.ndarray:
    cols = np.atleast_1d(_field(node, name, path)).astype(float).ravel()
    if cols.shape != (3,) or np.any(cols != np.round(cols)) or cols.min() < 1 or cols.max() > ncols:
        raise MotionFormatError(path, f"skel.tree({i + 1}).{name} must be 3 column numbers in "
                                      f"1..{ncols}, got {cols.tolist()}")
    return cols.astype(int) - 1


def _load(path: Path):
    from scipy.io import loadmat  # scipy is a dependency; imported late to keep imports light

    try:
        data = loadmat(str(path))
    except FileNotFoundError:
        raise MotionFormatError(path, "file not found") from None
    except Exception as exc:  # scipy raises a mix of ValueError/TypeError/MatReadError
        raise MotionFormatError(path, f"not a readable MATLAB file: {exc}") from None
    if "skel" not in data or "Motion" not in data:
        found = sorted(k for k in data if not k.startswith("__"))
        raise MotionFormatError(path, "expected variables 'skel' and 'Motion' (Taylor's MIT "
                                      f"format), found {found}")
    return data


def _tree(data, path):
    try:
        tree = np.asarray(data["skel"][0, 0]["tree"]).ravel()
    except (KeyError, ValueError, IndexError, TypeError):
        raise MotionFormatError(path, "'skel' has no 'tree' field") from None
    if len(tree) == 0:
        raise MotionFormatError(path, "'skel.tree' is empty")
    parents = []
    for i, node in enumerate(tree):
        p = np.atleast_1d(_field(node, "parent", path)).ravel()
        parents.append(int(p[0]) - 1 if p.size else -1)
        if not (parents[-1] == -1) == (i == 0) or not -1 <= parents[-1] < i:
            raise MotionFormatError(path, f"skel.tree({i + 1}).parent {p.tolist()} is not a "
                                          "parent listed before it (the root must come first)")
    return tree, parents


def read_mit(path: str | Path) -> list[Motion]:
    """Read Taylor's ``motion.mat`` into one :class:`Motion` per sequence (30 Hz).

    Joint DOFs: 3 per non-root node (X, Y, Z Euler angles, kept even where always zero so
    that the file's channels survive a round trip). Lengths in metres.

    Raises:
        MotionFormatError: not a MAT file, missing variables, a malformed tree, a sequence
            with the wrong width, non-finite values (frame named) or varying bone offsets.
    """
    path = Path(path)
    data = _load(path)
    tree, parents = _tree(data, path)
    J = len(tree)
    ncols = 6 * J
    seqs = [np.asarray(s, dtype=float) for s in np.asarray(data["Motion"], dtype=object).ravel()]
    if not seqs:
        raise MotionFormatError(path, "'Motion' holds no sequences")
    for k, X in enumerate(seqs):
        if X.ndim != 2 or X.shape[1] != ncols or X.shape[0] == 0:
            raise MotionFormatError(path, f"sequence {k + 1} has shape {X.shape}, expected "
                                          f"(frames, {ncols})")
        bad = ~np.isfinite(X)
        if bad.any():
            raise MotionFormatError(path, f"sequence {k + 1}: non-finite value in column "
                                          f"{int(np.argwhere(bad)[0][1]) + 1}",
                                    frame=int(np.argwhere(bad)[0][0]))
    rot_cols = [_columns(n, "or", ncols, path, i) for i, n in enumerate(tree)]
    off_cols = [_columns(n, "offset", ncols, path, i) for i, n in enumerate(tree)]
    standard = tuple(parents) == MIT_PARENTS
    names = MIT_JOINT_NAMES if standard else tuple(f"joint{i}" for i in range(J))
    first = seqs[0][0]
    joints = []
    for i in range(J):
        offset_mm = np.zeros(3) if i == 0 else first[off_cols[i]]
        if i > 0:
            spread = max(np.abs(X[:, off_cols[i]] - offset_mm).max() for X in seqs)
            if spread > 1e-6:
                raise MotionFormatError(path, f"node {names[i]!r}: bone offset varies over "
                                              f"time by {spread:.3g} mm")
        joints.append(Joint(names[i], parents[i], offset_mm / 1000.0,
                            axes=XYZ if i > 0 else np.zeros((0, 3)),
                            dof_names=tuple(f"{names[i]}_r{c}" for c in "xyz") if i > 0 else ()))
    skeleton = Skeleton(joints, world=MIT_WORLD, root_axes=ROOT_AXES, file_unit=0.001,
                        name="mit", mirror=np.diag([1.0, -1.0, 1.0]))
    motions = []
    for k, X in enumerate(seqs):
        root_R = root_matrix(X[:, rot_cols[0]])
        angles = np.concatenate([X[:, rot_cols[i]] for i in range(1, J)], axis=1)
        motions.append(Motion(skeleton, MIT_FPS, X[:, off_cols[0]] / 1000.0,
                              np.unwrap(matrix_to_chain(root_R, ROOT_AXES), axis=0), angles,
                              name=f"{path.stem}_{k + 1}", source_format="mit",
                              meta={"path": str(path), "sequence": k + 1}))
    return motions

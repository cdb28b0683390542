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
from motionlang.formats.matfile import read_mat
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import chain, matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton
from motionlang.utils import limits

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
MAX_ABS = 1e12  # largest magnitude accepted for any value (as the BVH and ASF readers)


def root_matrix(channels: np.ndarray) -> np.ndarray:
    """(..., 3) root channels (a, b, c) of the file -> (..., 3, 3) pelvis frame (Z up)."""
    channels = np.asarray(channels, dtype=float)
    return Q_CYCLE @ chain(ROOT_FILE_AXES, channels[..., [0, 2, 1]]) @ Q_CYCLE


def _describe(value) -> str:
    if isinstance(value, str):
        return f"text {value[:20]!r}"
    if isinstance(value, np.ndarray) and value.dtype == object:
        return "a struct" if value.size and isinstance(value.flat[0], dict) else "a cell array"
    return type(value).__name__


def _numbers(value, what: str, path) -> np.ndarray:
    """``value`` as a float array; MotionFormatError if it is text, a cell, a struct, or
    holds NaN or inf."""
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "biuf":
        raise MotionFormatError(path, f"{what} must be numbers, got {_describe(value)}")
    out = value.astype(float)
    if not np.all(np.isfinite(out)):
        raise MotionFormatError(path, f"{what} must be finite numbers")
    return out


def _structs(value, what: str, path) -> list[dict]:
    """The elements of a MATLAB struct array, in MATLAB's (column-major) order."""
    if not (isinstance(value, np.ndarray) and value.dtype == object and value.size
            and all(isinstance(v, dict) for v in value.flat)):
        raise MotionFormatError(path, f"{what} must be a struct, got {_describe(value)}")
    return list(value.ravel(order="F"))


def _field(node: dict, name: str, path, i: int):
    if name not in node:
        raise MotionFormatError(path, f"skel.tree({i + 1}) has no {name!r} field")
    return node[name]


def _columns(node: dict, name: str, ncols: int, path, i: int) -> np.ndarray:
    what = f"skel.tree({i + 1}).{name}"
    cols = _numbers(_field(node, name, path, i), what, path).ravel()
    if cols.shape != (3,) or np.any(cols != np.round(cols)) or cols.min() < 1 or cols.max() > ncols:
        raise MotionFormatError(path, f"{what} must be 3 column numbers in 1..{ncols}, got "
                                      f"{cols.tolist()[:6]}")
    return cols.astype(int) - 1


def _load(path: Path) -> dict:
    data = read_mat(path)  # no scipy: see formats.matfile for why
    if "skel" not in data or "Motion" not in data:
        found = sorted(k for k in data if not k.startswith("__"))
        raise MotionFormatError(path, "expected variables 'skel' and 'Motion' (Taylor's MIT "
                                      f"format), found {found}")
    return data


def _tree(data, path) -> tuple[list[dict], list[int]]:
    skel = _structs(data["skel"], "'skel'", path)[0]
    if "tree" not in skel:
        raise MotionFormatError(path, "'skel' has no 'tree' field")
    tree = _structs(skel["tree"], "'skel.tree'", path)
    limits.check(path, "max_joints", len(tree), "joint count")
    parents = []
    for i, node in enumerate(tree):
        p = _numbers(_field(node, "parent", path, i), f"skel.tree({i + 1}).parent", path).ravel()
        ok = p.size <= 1 and (p.size == 0 or p[0] == round(p[0]))
        parents.append(int(p[0]) - 1 if ok and p.size else -1)
        if not ok or not (parents[-1] == -1) == (i == 0) or not -1 <= parents[-1] < i:
            raise MotionFormatError(path, f"skel.tree({i + 1}).parent {p.tolist()[:4]} is not "
                                          "a parent listed before it (the root must come first)")
    return tree, parents


def _sequences(data, ncols: int, J: int, path) -> list[np.ndarray]:
    cells = data["Motion"]
    if not isinstance(cells, np.ndarray) or cells.dtype != object or \
            any(isinstance(c, dict) for c in cells.flat):
        raise MotionFormatError(path, "'Motion' must be a cell array of (frames, "
                                      f"{ncols}) number arrays, got {_describe(cells)}")
    if not cells.size:
        raise MotionFormatError(path, "'Motion' holds no sequences")
    seqs = []
    for k, X in enumerate(cells.ravel(order="F")):
        if not isinstance(X, np.ndarray) or X.dtype.kind not in "biuf":
            raise MotionFormatError(path, f"sequence {k + 1} must be numbers, got "
                                          f"{_describe(X)}")
        if X.ndim != 2 or X.shape[1] != ncols or X.shape[0] == 0:
            raise MotionFormatError(path, f"sequence {k + 1} has shape {X.shape}, expected "
                                          f"(frames, {ncols})")
        limits.check_motion(path, X.shape[0], J, ncols)
        X = X.astype(float)
        bad = ~(np.abs(X) <= MAX_ABS)  # NaN, inf, or so big that kinematics overflows
        if bad.any():
            f, c = np.argwhere(bad)[0]
            raise MotionFormatError(path, f"sequence {k + 1}: non-finite or out-of-range "
                                          f"value in column {int(c) + 1}", frame=int(f))
        seqs.append(X)
    return seqs


def read_mit(path: str | Path) -> list[Motion]:
    """Read Taylor's ``motion.mat`` into one :class:`Motion` per sequence (30 Hz).

    Joint DOFs: 3 per non-root node (X, Y, Z Euler angles, kept even where always zero so
    that the file's channels survive a round trip). Lengths in metres.

    Raises:
        MotionFormatError: not a MAT file or a malformed one (``formats.matfile``),
            missing variables, a malformed tree (text, a missing field or a bad number where
            ``parent``, ``or`` or ``offset`` should be), a sequence that is not numbers or
            has the wrong width, non-finite values (frame named), varying bone offsets, or
            a size beyond the limits (``utils.limits``).
    """
    path = Path(path)
    data = _load(path)
    tree, parents = _tree(data, path)
    J = len(tree)
    ncols = 6 * J
    seqs = _sequences(data, ncols, J, path)
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
        angles = X[:, [c for i in range(1, J) for c in rot_cols[i]]]
        motions.append(Motion(skeleton, MIT_FPS, X[:, off_cols[0]] / 1000.0,
                              np.unwrap(matrix_to_chain(root_R, ROOT_AXES), axis=0), angles,
                              name=f"{path.stem}_{k + 1}", source_format="mit",
                              meta={"path": str(path), "sequence": k + 1}))
    return motions

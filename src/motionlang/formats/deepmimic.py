"""DeepMimic motion clips (Peng et al. 2018): JSON ``.txt`` files of the ``humanoid3d``
character, as the DeepMimic project and the ``pybullet`` wheel (``pybullet_data/data/
motions/``) carry them. Read only. (The wheel's licence file puts its files under zlib; the
clips carry no licence or note of their mocap sources of their own.)

A file is a JSON object ``{"Loop": "wrap" | "none", "Frames": [[...], ...]}`` (other keys,
such as ``RightJoints``, are ignored). Each frame holds 44 numbers::

    duration (s), root position (3, metres), root rotation (quaternion w x y z),
    chest, neck, right hip (quaternions), right knee (radians), right ankle, right shoulder
    (quaternions), right elbow (radians), left hip, left knee, left ankle, left shoulder,
    left elbow (the same kinds as on the right)

The root's position and rotation are in the world (Y up); every other rotation is the
joint's own, relative to its parent. At rest (every quaternion the identity, every angle 0)
the character stands facing +x with its right side towards +z. A frame's duration is the
time to the next frame; the last frame's is usually 0.

**Body.** The character's bone offsets are not in the clips; they are those of
``pybullet_data/humanoid/humanoid.urdf`` (pybullet 3.2.7), which pybullet loads at a scale of
0.25 (``globalScaling=0.25`` in ``pybullet_envs/deep_mimic/env/humanoid_stable_pd.py``), written
here as constants (:data:`URDF_OFFSETS`) so that reading needs no pybullet. The knees and
elbows turn about their local +z (the URDF's revolute ``axis``: knees bend at negative
angles, elbows at positive ones). The URDF has no head, toe or heel joints; three DOF-free
end points come from its collision shapes: ``head_top`` (the top of the head sphere over the
neck) and ``left_foot_tip`` / ``right_foot_tip`` (the front edge of the sole of the foot
box). A BVH written from such a motion names them ``neck_end``, ``<side>_ankle_end`` and
(the wrists) ``<side>_elbow_end``; the joint map (``features.rig_maps``, ``deepmimic``)
knows both namings.

**Rotations.** Each quaternion becomes three Euler angles of a chain chosen so that its
middle angle (where a chain locks) stays far from +-90 degrees in the clips of the wheel:
the root Y-X-Z (heading first), shoulders X-Y-Z, every other ball joint Z-X-Y. The chain
reproduces the quaternion's rotation exactly whatever the angles.

**Frame rate.** The frame rate is 1 / the median frame duration (rounded to a whole number
when within 0.2 % of one). Clips whose durations all agree with it within 1 % keep their
frames as they are; any other clip (one of the wheel's has a frame twice as long as the
rest) is re-timed to that rate: positions and angles interpolated linearly, ball joints by
spherical interpolation of their quaternions. ``meta["retimed"]`` says which was done.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import AXES, matrix_to_chain
from motionlang.kinematics.skeleton import Joint, Skeleton
from motionlang.utils import limits
from motionlang.utils.sidecar import open_regular, parse_json, read_bytes

#: pybullet's scale of ``humanoid.urdf`` for DeepMimic (metres per URDF unit)
URDF_SCALE = 0.25
#: numbers in one frame of a humanoid3d clip
FRAME_WIDTH = 44
#: the tree in file order: (joint, parent, DOFs: "quat", "angle" or "" for an end point).
#: The 12 moving joints after the root appear in this order in every frame.
TREE: tuple[tuple[str, str, str], ...] = (
    ("root", "", "quat"),
    ("chest", "root", "quat"), ("neck", "chest", "quat"), ("head_top", "neck", ""),
    ("right_hip", "root", "quat"), ("right_knee", "right_hip", "angle"),
    ("right_ankle", "right_knee", "quat"), ("right_foot_tip", "right_ankle", ""),
    ("right_shoulder", "chest", "quat"), ("right_elbow", "right_shoulder", "angle"),
    ("right_wrist", "right_elbow", ""),
    ("left_hip", "root", "quat"), ("left_knee", "left_hip", "angle"),
    ("left_ankle", "left_knee", "quat"), ("left_foot_tip", "left_ankle", ""),
    ("left_shoulder", "chest", "quat"), ("left_elbow", "left_shoulder", "angle"),
    ("left_wrist", "left_elbow", ""),
)
#: offsets from the parent in URDF units (x forward, y up, z to the character's right), read
#: from ``pybullet_data/humanoid/humanoid.urdf``: each joint's ``<origin xyz>``; ``head_top``
#: = the neck link's sphere centre (0, 0.70, 0) + its radius 0.41; ``*_foot_tip`` = the
#: ankle link's box centre (0.18, -0.09, 0) + half its size (0.708, 0.22, 0.36) forward and
#: down. Left-side joints mirror the right (z negated), as in the URDF.
URDF_OFFSETS: dict[str, tuple[float, float, float]] = {
    "root": (0.0, 0.0, 0.0),
    "chest": (0.0, 0.944604, 0.0), "neck": (0.0, 0.895576, 0.0), "head_top": (0.0, 1.11, 0.0),
    "right_hip": (0.0, 0.0, 0.339548), "right_knee": (0.0, -1.686184, 0.0),
    "right_ankle": (0.0, -1.639480, 0.0), "right_foot_tip": (0.534, -0.2, 0.0),
    "right_shoulder": (-0.0962, 0.974, 0.73244), "right_elbow": (0.0, -1.099152, 0.0),
    "right_wrist": (0.0, -1.035788, 0.0),
}
URDF_OFFSETS.update({"left" + k[5:]: (x, y, -z) for k, (x, y, z) in list(URDF_OFFSETS.items())
                     if k.startswith("right_")})
#: Euler chains (module docstring, "Rotations"); a revolute joint turns about +z
ROOT_CHAIN = "yxz"
SHOULDER_CHAIN = "xyz"
BALL_CHAIN = "zxy"
#: frame durations agreeing with the median within this fraction keep their frames
STEP_TOLERANCE = 0.01
#: a rate within this fraction of a whole number is that number (0.016666 s is 60 Hz)
RATE_TOLERANCE = 2e-3
#: the rate of a one-frame clip without a duration
DEFAULT_FPS = 30.0
#: a quaternion shorter than this is no rotation (longer ones are normalised: some of the
#: wheel's clips hold quaternions well off unit length, which DeepMimic normalises too)
MIN_QUAT_NORM = 1e-3
MAX_ABS = 1e12  # largest magnitude accepted for any value (as the other readers)
PARSE_FACTOR = 8  # memory of the parsed JSON lists per byte of file
#: bytes of a file's start that :func:`looks_like_deepmimic` reads
SNIFF_BYTES = 4096
WHAT = 'not a DeepMimic motion (a JSON object with a "Frames" list)'
_KIND = {list: "array", str: "string", int: "number", float: "number", bool: "boolean",
         type(None): "null"}


def _axes(chain: str) -> np.ndarray:
    return np.stack([AXES[c] for c in chain])


def _chain(name: str) -> str:
    return ROOT_CHAIN if name == "root" else SHOULDER_CHAIN if name.endswith("shoulder") \
        else BALL_CHAIN


def deepmimic_skeleton() -> Skeleton:
    """The humanoid3d character: 18 nodes (:data:`TREE`), metres, Y up, facing +x; 28 joint
    DOFs (8 ball joints x 3, 4 hinges); root orientation as a Y-X-Z chain."""
    index = {name: i for i, (name, _, _) in enumerate(TREE)}
    joints = []
    for name, parent, kind in TREE:
        offset = np.array(URDF_OFFSETS[name]) * URDF_SCALE
        if kind == "quat" and name != "root":
            chain = _chain(name)
            joints.append(Joint(name, index[parent], offset, axes=_axes(chain),
                                dof_names=tuple(f"{name}_r{c}" for c in chain)))
        elif kind == "angle":
            joints.append(Joint(name, index[parent], offset, axes=_axes("z"),
                                dof_names=(f"{name}_rz",)))
        else:
            joints.append(Joint(name, index[parent] if parent else -1, offset))
    return Skeleton(joints, world=np.eye(3), root_axes=_axes(ROOT_CHAIN), file_unit=1.0,
                    name="deepmimic:humanoid3d", mirror=np.diag([1.0, 1.0, -1.0]))


def _columns() -> dict[str, slice]:
    """The columns of each moving joint in a frame (the root's rotation: ``"root"``)."""
    out, c = {}, 4
    for name, _, kind in TREE:
        width = 4 if kind == "quat" else 1 if kind == "angle" else 0
        if width:
            out[name] = slice(c, c + width)
            c += width
    return out


COLUMNS = _columns()


def looks_like_deepmimic(path: str | Path) -> bool:
    """Whether ``path`` starts as a DeepMimic clip does: a JSON object with a ``"Frames"``
    key near its start (for folder scans; :func:`read_deepmimic` checks the rest)."""
    try:
        with open_regular(path, "motion file") as fh:
            head = fh.read(SNIFF_BYTES)
    except (MotionlangError, OSError):
        return False
    return head.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"{") and b'"Frames"' in head


def _reason(exc: MotionlangError, path: Path) -> str:
    return str(exc).removeprefix(f"{path}: ")


def _load(path: Path) -> dict:
    limits.check_file(path, PARSE_FACTOR)
    try:
        raw = read_bytes(path, "motion file")
    except MotionlangError as exc:   # one line already, naming the file: keep the reason
        raise MotionFormatError(path, _reason(exc, path)) from None
    try:
        data = parse_json(raw, str(path))
    except MotionlangError as exc:
        reason = _reason(exc, path)
        not_json = reason.startswith(("invalid JSON", "not UTF-8"))
        raise MotionFormatError(path, f"{WHAT}: {reason}" if not_json else reason) from None
    if not isinstance(data, dict) or "Frames" not in data:
        found = f"an object with keys {[k[:30] for k in sorted(data)[:6]]}" \
            if isinstance(data, dict) else f"a JSON {_KIND.get(type(data), 'value')}"
        raise MotionFormatError(path, f"{WHAT}; found {found}")
    loop = data.get("Loop", "none")
    if not isinstance(loop, str):
        raise MotionFormatError(path, f'"Loop" must be "wrap" or "none", got {loop!r:.40}')
    return data


def _frames(data: dict, path: Path) -> np.ndarray:
    """(T, 44) the numbers of every frame (their values are checked by ``_check``)."""
    rows = data["Frames"]
    if not isinstance(rows, list) or not rows:
        raise MotionFormatError(path, '"Frames" must be a non-empty list of frames')
    limits.check_motion(path, len(rows), len(TREE), FRAME_WIDTH)
    for k, row in enumerate(rows):
        if not isinstance(row, list) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in row):
            raise MotionFormatError(path, "a frame must be a list of numbers", frame=k)
        if len(row) != FRAME_WIDTH:
            raise MotionFormatError(path, f"{len(row)} numbers in a frame where the DeepMimic "
                                          f"humanoid's have {FRAME_WIDTH} (duration, root "
                                          "position, root and 12 joint rotations); other "
                                          "characters' clips are not read", frame=k)
    return np.array(rows, dtype=float)


def _check(X: np.ndarray, path: Path | None) -> None:
    """Values in range and quaternions that are rotations, or the first frame without."""
    bad = ~(np.abs(X) <= MAX_ABS)
    if bad.any():
        k, c = np.argwhere(bad)[0]
        raise MotionFormatError(path, f"value out of range in column {int(c) + 1}",
                                frame=int(k))
    for name, cols in COLUMNS.items():
        if cols.stop - cols.start == 4:
            norm = np.linalg.norm(X[:, cols], axis=1)
            if norm.min() < MIN_QUAT_NORM:
                k = int(np.argmin(norm))
                raise MotionFormatError(path, f"the {name} rotation (columns {cols.start + 1}-"
                                              f"{cols.stop}) is no quaternion of a rotation "
                                              f"(norm {norm[k]:.3g})", frame=k)


def frame_rate(durations: np.ndarray, path: str | Path | None = None) -> tuple[float, bool]:
    """(frames per second, whether the frames are evenly spaced at it) of a clip's frame
    durations (T,) in seconds (the last one is not a step and is not read unless T = 1).

    Raises:
        MotionFormatError: a negative duration, or a zero one before the last frame.
    """
    d = np.asarray(durations, dtype=float)
    if (d < 0).any():
        raise MotionFormatError(path, f"negative frame duration {d[d < 0][0]:g} s",
                                frame=int(np.argmax(d < 0)))
    steps = d[:-1]
    if len(steps) and (steps <= 0).any():
        raise MotionFormatError(path, "a frame before the last lasts 0 s: every frame but "
                                      "the last needs a positive duration",
                                frame=int(np.argmax(steps <= 0)))
    if not len(steps):
        return (1.0 / d[0] if d[0] > 0 else DEFAULT_FPS), True
    dt = float(np.median(steps))
    fps = 1.0 / dt
    if round(fps) >= 1 and abs(fps - round(fps)) <= RATE_TOLERANCE * fps:
        fps = float(round(fps))
    return fps, bool(np.all(np.abs(steps - dt) <= STEP_TOLERANCE * dt))


def _retime(X: np.ndarray, fps: float, path: Path) -> np.ndarray:
    """Frames (T, 44) at their own times -> frames on the grid k / fps within the clip."""
    times = np.concatenate([[0.0], np.cumsum(X[:-1, 0])])
    n = int(np.floor(times[-1] * fps + 1e-6)) + 1
    limits.check_motion(path, n, len(TREE), FRAME_WIDTH)
    grid = np.minimum(np.arange(n) / fps, times[-1])
    out = np.empty((n, FRAME_WIDTH))
    out[:, 0] = 1.0 / fps
    for c in range(1, 4):
        out[:, c] = np.interp(grid, times, X[:, c])
    # scipy.spatial loads in a few tenths of a second, which every command would pay
    # (formats is read by all of them) and only a DeepMimic clip needs
    from scipy.spatial.transform import Rotation, Slerp
    for cols in COLUMNS.values():
        if cols.stop - cols.start == 1:
            out[:, cols.start] = np.interp(grid, times, X[:, cols.start])
        else:
            slerp = Slerp(times, Rotation.from_quat(X[:, cols][:, [1, 2, 3, 0]]))
            out[:, cols] = slerp(grid).as_quat()[:, [3, 0, 1, 2]]
    return out


def quat_matrix(q: np.ndarray) -> np.ndarray:
    """Quaternions (..., 4) in DeepMimic's (w, x, y, z) order, normalised -> rotation
    matrices (..., 3, 3)."""
    from scipy.spatial.transform import Rotation  # only for a DeepMimic clip, as above
    q = np.asarray(q, dtype=float)
    flat = q.reshape(-1, 4)[:, [1, 2, 3, 0]]
    return Rotation.from_quat(flat).as_matrix().reshape(q.shape[:-1] + (3, 3))


def motion_from_frames(frames, *, name: str = "deepmimic", loop: str = "none",
                       path: str | Path | None = None) -> Motion:
    """A :class:`Motion` of the humanoid3d character from frames (T, 44) laid out as a
    DeepMimic file's (module docstring), at the frame rate of :func:`frame_rate`.

    Raises:
        MotionFormatError: a value out of range, a quaternion of (nearly) zero length
            or bad durations (:func:`frame_rate`), naming the frame.
    """
    X = np.asarray(frames, dtype=float)
    where = Path(path) if path is not None else None
    if X.ndim != 2 or X.shape[1] != FRAME_WIDTH or not len(X):
        raise MotionFormatError(where, f"frames must be (T >= 1, {FRAME_WIDTH}), got {X.shape}")
    _check(X, where)
    fps, even = frame_rate(X[:, 0], where)
    n_file = len(X)
    if not even:
        X = _retime(X, fps, where or Path(name))
    sk = deepmimic_skeleton()
    root = np.unwrap(matrix_to_chain(quat_matrix(X[:, COLUMNS["root"]]), sk.root_axes), axis=0)
    angles = []
    for j in sk.joints[1:]:
        cols = COLUMNS.get(j.name)
        if cols is None:
            continue
        if j.ndof == 1:   # a hinge's angle as the file has it
            angles.append(X[:, cols])
        else:             # unwrapped: an angle past +-pi goes on, as the motion does
            angles.append(np.unwrap(matrix_to_chain(quat_matrix(X[:, cols]), j.axes), axis=0))
    meta = {"loop": loop, "file_frames": n_file, "retimed": not even}
    if path is not None:
        meta["path"] = str(path)
    return Motion(sk, fps, X[:, 1:4], root, np.concatenate(angles, axis=1),
                  name=name, source_format="deepmimic", meta=meta)


def read_deepmimic(path: str | Path) -> Motion:
    """Read a DeepMimic clip of the humanoid3d character (module docstring).

    ``meta``: ``path``, ``loop`` (the file's ``"Loop"``: ``"wrap"`` for a cyclic clip),
    ``file_frames`` (frames in the file), ``retimed`` (whether uneven frames were put on an
    even grid).

    Raises:
        MotionFormatError: not a regular file, not JSON, not a DeepMimic clip, frames that
            are not lists of 44 numbers, quaternions of (nearly) zero length, bad
            durations, or a size beyond the limits (``utils.limits``); one line naming the
            file and, where it applies, the frame.
    """
    path = Path(path)
    data = _load(path)
    return motion_from_frames(_frames(data, path), name=path.stem, loop=data.get("Loop", "none"),
                              path=path)


__all__ = ["deepmimic_skeleton", "frame_rate", "looks_like_deepmimic", "motion_from_frames",
           "quat_matrix", "read_deepmimic", "COLUMNS", "FRAME_WIDTH", "TREE", "URDF_OFFSETS",
           "URDF_SCALE"]

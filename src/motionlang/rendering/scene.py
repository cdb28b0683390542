"""What a renderer needs to know about a motion, computed once: joint positions in
matplotlib's frame, bones, body sides, feet, floor height, travel direction.

Coordinates: motionlang's canonical frame is Y up (metres). matplotlib's 3-D axes have z
up, so a canonical point ``(X, Y, Z)`` is drawn at ``(X, -Z, Y)`` — a proper rotation
(determinant +1), so nothing is mirrored.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS, positions21
from motionlang.kinematics import Motion

# canonical (X, Y, Z) -> matplotlib (x, y, z): rows give the new axes
TO_MPL = np.array([[1.0, 0.0, 0.0],
                   [0.0, 0.0, -1.0],
                   [0.0, 1.0, 0.0]])

LEFT, RIGHT, CENTRE = "L", "R", "C"
#: the body's sides as every picture draws them, the web viewer's too (static/viewer.js):
#: left blue, right orange
SIDE_COLOURS = {LEFT: "#2a6fdb", RIGHT: "#e07b22", CENTRE: "#404040"}
# second motion in an overlay: same idea, lighter tones
SIDE_COLOURS_ALT = {LEFT: "#8fb3ee", RIGHT: "#f2b27f", CENTRE: "#9a9a9a"}


@dataclass
class Scene:
    """A motion prepared for drawing.

    Attributes:
        points: (T, J, 3) joint positions in metres, matplotlib frame (z up).
        bones: list of (parent, child) joint indices with non-zero length.
        bone_sides: side (``"L"``, ``"R"``, ``"C"``) of each bone.
        feet: joint indices used as feet (lowest joint of each side; may be one joint).
        floor: z of the floor in metres (lowest foot point over the motion).
        root: (T, 3) root joint positions (matplotlib frame).
        forward: (2,) unit horizontal direction of travel (or facing) in the xy plane.
        height: body height in metres (highest point above the floor over the motion).
        fps: frames per second; name: label.
    """

    points: np.ndarray
    bones: list[tuple[int, int]]
    bone_sides: list[str]
    feet: list[int]
    floor: float
    root: np.ndarray
    forward: np.ndarray
    height: float
    fps: float
    name: str

    @property
    def n_frames(self) -> int:
        return len(self.points)


def joint_sides(motion: Motion) -> list[str]:
    """Side of every joint: from ``skeleton.pairs``, else inherited from the parent."""
    sk = motion.skeleton
    left = {a for a, _ in sk.pairs or []}
    right = {b for _, b in sk.pairs or []}
    sides: list[str] = []
    for j in sk.joints:
        if j.name in left:
            sides.append(LEFT)
        elif j.name in right:
            sides.append(RIGHT)
        else:
            sides.append(sides[j.parent] if j.parent >= 0 else CENTRE)
    return sides


def _pick_feet(points: np.ndarray, sides: list[str] | None) -> list[int]:
    """Lowest joint (by mean height) of each body side; without sides, the two lowest
    joints that are at least 10 cm apart (two feet), else the lowest one."""
    mean_h = points[..., 2].mean(axis=0)
    if sides is not None:
        feet = []
        for s in (LEFT, RIGHT):
            idx = [i for i, si in enumerate(sides) if si == s]
            if idx:
                feet.append(min(idx, key=lambda i: mean_h[i]))
        if feet:
            return feet
    order = list(np.argsort(mean_h))
    first = int(order[0])
    for i in order[1:]:
        gap = np.linalg.norm(points[:, i, :2] - points[:, first, :2], axis=-1).mean()
        if gap > 0.1 and mean_h[i] - mean_h[first] < 0.15:
            return [first, int(i)]
    return [first]


def _forward(root: np.ndarray, points: np.ndarray,
             pairs: list[tuple[int, int]] = ()) -> np.ndarray:
    """Unit xy direction of travel; the facing direction for motions (nearly) in place."""
    travel = root[-1, :2] - root[0, :2]
    if np.linalg.norm(travel) > 0.5:
        return travel / np.linalg.norm(travel)
    if pairs:
        # left-minus-right summed over all pairs and frames: single pairs can coincide
        # (ASF hip nodes sit at the root) or cross (arms), the sum points to the left
        li, ri = np.array(pairs).T
        across = (points[:, li] - points[:, ri]).sum(axis=(0, 1))
        # forward = across x up (left = +X and forward = +Z in the canonical frame)
        fwd = np.array([across[1], -across[0]])
        if np.linalg.norm(fwd) > 1e-6:
            return fwd / np.linalg.norm(fwd)
    if np.linalg.norm(travel) > 1e-6:
        return travel / np.linalg.norm(travel)
    return np.array([1.0, 0.0])


def _pair_indices(motion: Motion) -> list[tuple[int, int]]:
    sk = motion.skeleton
    return [(sk.index(a), sk.index(b)) for a, b in sk.pairs or [] if a in sk and b in sk]


def build_scene(motion: Motion) -> Scene:
    """Compute everything the renderers draw from one ``Motion``: the 21-joint body that
    every other command reads (``features.joint_map``: its sides, feet and root, and no
    helper bone of the rig, such as a root on the floor, eyes or twist bones), or the rig's
    own joints (one FK pass) where no body map fits it."""
    try:
        p21 = positions21(motion)
    except MotionlangError:
        return rig_scene(motion)
    return kit21_scene(p21, float(motion.fps), motion.name)


def rig_scene(motion: Motion) -> Scene:
    """The rig's own joints and bones, sides and feet read from its joint names."""
    sk = motion.skeleton
    points = motion.positions() @ TO_MPL.T
    sides = joint_sides(motion)
    bones, bone_sides = [], []
    for c, joint in enumerate(sk.joints):
        # MMM and ASF skeletons have several nodes at one place; drawing them is noise
        if joint.parent >= 0 and np.linalg.norm(joint.offset) > 1e-6:
            bones.append((joint.parent, c))
            bone_sides.append(sides[c])
    has_sides = LEFT in sides or RIGHT in sides
    feet = _pick_feet(points, sides if has_sides else None)
    floor = float(points[:, feet, 2].min())
    root = points[:, 0]
    height = float(points[..., 2].max() - floor)
    return Scene(points=points, bones=bones, bone_sides=bone_sides, feet=feet, floor=floor,
                 root=root, forward=_forward(root, points, _pair_indices(motion)),
                 height=max(height, 1e-3), fps=float(motion.fps), name=motion.name)


def view_azimuth(forward: np.ndarray, front_deg: float = 30.0) -> float:
    """matplotlib azimuth (degrees) of a camera beside the body, ``front_deg`` towards its
    front, so that travel goes left-to-right on screen."""
    f = np.array([forward[0], forward[1], 0.0])
    side = np.cross(f, [0.0, 0.0, 1.0])  # camera position whose screen-right is f
    a = np.radians(front_deg)
    eye = side * np.cos(a) + f * np.sin(a)
    return float(np.degrees(np.arctan2(eye[1], eye[0])))


#: animation frames drawn without ``max_frames`` (10 minutes at 25 Hz): drawing takes tens
#: of milliseconds a frame, so a long take would run for hours unasked
RENDER_MAX_FRAMES = 15_000


def sample_times(n_frames: int, fps: float, out_fps: float,
                 max_frames: int | None = None) -> np.ndarray:
    """Frame indices showing a motion at ``out_fps`` in real time (nearest frame).

    Raises:
        MotionlangError: more than ``max_frames`` (default :data:`RENDER_MAX_FRAMES`)
            would be drawn; the message names the option that allows them.
    """
    duration = (n_frames - 1) / fps
    n_float = np.floor(duration * out_fps + 1e-9) + 1
    limit = RENDER_MAX_FRAMES if max_frames is None else max_frames
    if not n_float <= limit:
        raise MotionlangError(
            f"{n_float:,.0f} frames to draw ({duration:,.1f} s at {out_fps:g} Hz) exceed "
            f"{limit:,}: pass --max-frames (max_frames=) to draw more, or lower --fps, or "
            "draw a part with --start/--end")
    n_out = int(n_float)
    return np.clip(np.rint(np.arange(n_out) * fps / out_fps).astype(int), 0, n_frames - 1)


def contact_frames(scene: Scene, *, height_tol: float = 0.05,
                   speed_tol: float = 0.3) -> dict[int, np.ndarray]:
    """Foot contacts: frames where a foot is low and slow.

    A foot is *low* within ``height_tol`` metres of its own lowest height (ankle joints never
    touch z = floor) and *slow* below ``speed_tol`` m/s horizontally.

    Returns:
        {foot joint index: (T,) bool}.
    """
    out = {}
    for f in scene.feet:
        p = scene.points[:, f]
        low = p[:, 2] <= p[:, 2].min() + height_tol
        if len(p) > 1:
            v = np.linalg.norm(np.gradient(p[:, :2], axis=0), axis=-1) * scene.fps
        else:
            v = np.zeros(len(p))
        out[f] = low & (v < speed_tol)
    return out


def footsteps(scene: Scene, **kw) -> list[tuple[int, np.ndarray]]:
    """One (foot index, mean xy position (2,)) per run of consecutive contact frames."""
    steps = []
    for f, c in contact_frames(scene, **kw).items():
        edges = np.flatnonzero(np.diff(np.concatenate([[0], c.astype(int), [0]])))
        for a, b in zip(edges[::2], edges[1::2]):
            steps.append((f, scene.points[a:b, f, :2].mean(axis=0)))
    return steps


def scene_from_positions(positions: np.ndarray, fps: float = 30.0, name: str = "positions",
                         parents: np.ndarray | None = None,
                         sides: list[str] | None = None) -> Scene:
    """A Scene from raw joint positions (T, J, 3) metres, canonical Y-up frame, joint 0 =
    root (e.g. a model's output). Bones need ``parents`` (J,); ``sides`` (J,) of ``"L"``,
    ``"R"``, ``"C"`` colour the bones by their child joint and pick one foot per side;
    without them the feet are the two lowest joints."""
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 3 or pos.shape[-1] != 3 or len(pos) == 0:
        raise ValueError(f"positions must be (T, J, 3) with T > 0, got {pos.shape}")
    points = pos @ TO_MPL.T
    bones = [] if parents is None else [(int(p), c) for c, p in enumerate(parents) if p >= 0]
    feet = _pick_feet(points, sides)
    floor = float(points[:, feet, 2].min())
    root = points[:, 0]
    bone_sides = [CENTRE if sides is None else sides[c] for _, c in bones]
    return Scene(points=points, bones=bones, bone_sides=bone_sides, feet=feet,
                 floor=floor, root=root, forward=_forward(root, points),
                 height=max(float(points[..., 2].max() - floor), 1e-3), fps=float(fps),
                 name=name)


def camera_basis(azim_deg: float, elev: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Screen-right, screen-up and towards-camera unit vectors (matplotlib frame, z up) of
    a camera at matplotlib's ``(elev, azim)`` angles in degrees."""
    az, el = np.radians(azim_deg), np.radians(elev)
    eye = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross([0.0, 0.0, 1.0], eye)
    right /= np.linalg.norm(right)
    up = np.cross(eye, right)
    return right, up, eye


def kit21_scene(positions: np.ndarray, fps: float, name: str = "generated") -> Scene:
    """A Scene of the 21 KIT joints (T, 21, 3) metres, Y up, in ``joint_map.KIT21_NAMES``
    order: the output of the *positions* models (two-stream, positions L2M)."""
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 3 or pos.shape[1:] != (len(KIT21_NAMES), 3):
        raise ValueError(f"positions must be (T, {len(KIT21_NAMES)}, 3), got {pos.shape}")
    sides = [n[0] if n[0] in (LEFT, RIGHT) else CENTRE for n in KIT21_NAMES]
    return scene_from_positions(pos, fps, name, np.array(KIT21_PARENTS), sides)

"""Generated results to files: the one place that writes a result by its file extension.

A result is a :class:`Motion` (a joint-angle model's output, or a retargeted one) or global
21-joint positions (T, 21, 3) metres at a given frame rate (a joint-position model's).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS, kit21_weights, positions21
from motionlang.formats import write_motion
from motionlang.kinematics.from_positions import motion_from_positions
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.retarget import retarget
from motionlang.rendering.scene import kit21_scene
from motionlang.utils.atomic import atomic_write

#: motion files (.bvh, .glb and .gltf also for positions, fitted on a 21-joint skeleton)
MOTION_OUT = (".bvh", ".glb", ".gltf", ".xml", ".amc")
#: the motion files that any skeleton can be written to
ANY_SKELETON_OUT = (".bvh", ".glb", ".gltf")
#: animations; ``.png`` is a pose strip, ``.npz`` the positions and frame rate
RENDER_OUT = (".gif", ".mp4")
RESULT_OUT = MOTION_OUT + RENDER_OUT + (".png", ".npz")
#: what :func:`render_file` draws: an animation, or a ``.png`` pose strip or trajectory
DRAW_OUT = RENDER_OUT + (".png",)


def check_result_path(path: str | Path, *, rig: bool = False) -> None:
    """Raise :class:`MotionlangError` naming ``path`` unless :func:`write_result` can write
    a result there (with ``rig``: a file that holds any skeleton), before anything slow."""
    ext = Path(path).suffix.lower()
    if ext not in RESULT_OUT:
        raise MotionlangError(f"{path}: output must be .bvh, .glb, .gltf, .xml, .amc, .gif, "
                              ".mp4, .png or .npz")
    if rig and ext not in ANY_SKELETON_OUT:
        raise MotionlangError(f"{path}: a result on a rig is written as "
                              f"{', '.join(ANY_SKELETON_OUT)}; got {ext or 'none'!r}")


def check_drawable(path: str | Path) -> None:
    """Raise :class:`MotionlangError` naming ``path`` unless :func:`render_file` can draw
    to its extension (before anything slow is read)."""
    ext = Path(path).suffix.lower()
    if ext not in DRAW_OUT:
        raise MotionlangError(f"{path}: cannot render to {ext or '(no extension)'!r}; use "
                              f"{', '.join(DRAW_OUT)}")


def render_file(motion, path: str | Path, *, title: str | None = None, n_poses: int = 8,
                fps: float | None = None, camera: str = "auto", trajectory: bool = False,
                max_frames: int | None = None) -> Path:
    """Draw a Motion (or a ``rendering.scene.Scene``) by ``path``'s extension: ``.gif`` /
    ``.mp4`` animation at ``fps`` (default min(25, the motion's)) with ``camera`` (at most
    ``max_frames`` frames, default ``scene.RENDER_MAX_FRAMES``: more is an error), or a
    ``.png`` strip of ``n_poses`` poses (with ``trajectory``: the root's path seen from
    above, with footsteps). Atomic; returns the path.
    """
    check_drawable(path)
    if Path(path).suffix.lower() != ".png":
        from motionlang.rendering.animation import render_animation
        return render_animation(motion, path, fps=fps, title=title, camera=camera,
                                max_frames=max_frames)
    if trajectory:
        from motionlang.rendering.trajectory import plot_trajectory
        return plot_trajectory(motion, path, title=title)
    from motionlang.rendering.strip import render_strip
    return render_strip(motion, path, n_frames=n_poses, title=title)


def body_motion(result, fps: float, rig: Motion | None = None, name: str = "generated"
                ) -> tuple[Motion, np.ndarray]:
    """A generated motion as a :class:`Motion`: positions (T, 21, 3) metres at ``fps`` Hz
    get joint angles fitted on a 21-joint skeleton, or, with ``rig``, are retargeted onto
    the rig's skeleton (its names, units and rest pose; ``rig.meta["joint_map"]`` honoured).
    A Motion (angles L2M) is returned as it is unless ``rig`` is given.

    Returns:
        the Motion and the per-frame, per-joint distance (T, 21) in metres between its
        21 body joints and the generated ones (zeros for a Motion kept as it is).
    """
    if isinstance(result, Motion):
        if rig is None:
            return result, np.zeros((result.n_frames, len(KIT21_NAMES)))
        fps, result = result.fps, positions21(result)
    if rig is None:
        motion = motion_from_positions(result, fps, KIT21_NAMES, KIT21_PARENTS, name=name)
        W = np.eye(len(KIT21_NAMES))
    else:
        W = kit21_weights(rig.skeleton, joint_map=rig.meta.get("joint_map"))[1]
        motion = retarget(result, fps, rig, weights=W, name=name)
    err = np.linalg.norm(np.einsum("kj,tjc->tkc", W, motion.positions()) - result, axis=-1)
    return motion, err


#: the body's parts compared when a take is put on a rig: chains of 21-joint points
PARTS = {"legs": (("LH", "LK", "LA"), ("RH", "RK", "RA")),
         "arms": (("LS", "LE", "LW"), ("RS", "RE", "RW")),
         "trunk": (("root", "BP", "BT", "BLN", "BUN"),)}
#: parts whose lengths differ by less than this fraction are "the same"
SAME_WITHIN = 0.03


def part_lengths(points: np.ndarray, used: np.ndarray | None = None) -> dict[str, float]:
    """Metres of each of :data:`PARTS` in ``points`` (T, 21, 3): the chain's length, the
    median over frames, the mean of its sides; a part with a point not ``used`` (21,) is
    left out (a rig that does not map it)."""
    index = {n: i for i, n in enumerate(KIT21_NAMES)}
    out = {}
    for part, chains in PARTS.items():
        ids = [[index[n] for n in chain] for chain in chains]
        if used is not None and not all(used[i] for c in ids for i in c):
            continue
        lengths = [np.median(np.linalg.norm(np.diff(points[:, c], axis=1), axis=-1).sum(1))
                   for c in ids]
        out[part] = float(np.mean(lengths))
    return out


def rig_differences(source: np.ndarray, mapped: np.ndarray,
                    used: np.ndarray | None = None) -> str:
    """How a rig's body differs from the generated one, in words: "its legs are 6 %
    shorter and its arms 12 % longer than the generated body's", or "its legs, arms and
    trunk are within 3 % of the generated body's". ``source``, ``mapped``: (T, 21, 3)
    metres, the generated points and the rig's points that follow them."""
    mine, theirs = part_lengths(mapped, used), part_lengths(source, used)
    change = {p: mine[p] / theirs[p] - 1.0 for p in mine if theirs.get(p, 0.0) > 1e-6}
    differ = [(p, c) for p, c in change.items() if abs(c) >= SAME_WITHIN]
    if not differ:
        return f"its {_listed(list(change))} are within {SAME_WITHIN:.0%} of the " \
               "generated body's" if change else "its parts could not be compared"
    said = [f"{p} {'are ' if i == 0 else ''}{abs(c):.0%} {'longer' if c > 0 else 'shorter'}"
            for i, (p, c) in enumerate(differ)]
    return f"its {_listed(said)} than the generated body's"


def _listed(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _error_note(err_m: np.ndarray, what: str) -> str:
    err = err_m * 1000.0
    return f" ({what}{err.mean():.1f} mm from the generated ones on average, at most " \
           f"{err.max():.0f} mm"


def write_result(result, path: str | Path, *, fps: float, title: str = "",
                 rig: Motion | None = None) -> str:
    """A generated Motion, or 21-joint positions (T, 21, 3) at ``fps`` Hz, to ``path``:
    .npz (positions and fps), .bvh / .glb / .gltf (a Motion as it is; positions on a
    21-joint skeleton fitted to them; glTF: metres, Y up, a skinned stick mesh, see
    ``formats.gltf``), .xml / .amc (Motions on such skeletons only), .gif / .mp4 animation or
    .png pose strip; with ``rig``, retargeted onto the rig's skeleton first. Atomic.

    Returns:
        a note for the user: "" or how far a fitted skeleton's joints are from the result.

    Raises:
        MotionlangError: an extension that cannot hold this result, naming the path.
    """
    path = Path(path)
    ext = path.suffix.lower()
    check_result_path(path)
    note = ""
    if rig is not None:
        source = positions21(result) if isinstance(result, Motion) else result
        result, err = body_motion(result, fps, rig)
        W = kit21_weights(rig.skeleton, joint_map=rig.meta.get("joint_map"))[1]
        mapped = np.einsum("kj,tjc->tkc", W, result.positions())
        note = _error_note(err, f"on the rig of {rig.meta.get('path', rig.name)}: "
                                f"{rig_differences(source, mapped, (W != 0).any(axis=1))}, "
                                "so its body joints lie ") + "; its bones point as the " \
                                "generated ones do)"
    if ext == ".npz":
        data = {"positions": result, "fps": np.float64(fps)} if isinstance(result, np.ndarray) \
            else {"positions": result.positions(), "fps": np.float64(result.fps)}
        with atomic_write(path, "wb") as fh:
            np.savez(fh, **data)
        return note
    if not isinstance(result, Motion):
        if ext in MOTION_OUT:
            if ext not in ANY_SKELETON_OUT:
                raise MotionlangError(f"{path}: this model's features decode to joint "
                                      "positions; write .bvh, .glb, .gltf, .npz, .gif, .mp4 "
                                      "or .png")
            result, err = body_motion(result, fps, name=path.stem)
            note = _error_note(err, "joints ") + (": bone lengths held at their medians, "
                                                  "pelvis and neck turned by least squares)")
        else:
            result = kit21_scene(result, fps)
    if ext in MOTION_OUT:
        write_motion(result, path)
    else:
        render_file(result, path, title=title)
    return note

"""Top view of root trajectories with footstep markers (as in Ghosh et al. 2021's
trajectory figure)."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.kinematics import Motion
from motionlang.rendering.draw import new_figure
from motionlang.rendering.scene import Scene, build_scene, footsteps, scene_from_positions
from motionlang.utils.atomic import atomic_path

PATH_COLOURS = ["#404040", "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e"]


def _scene(item, fps: float | None, k: int) -> Scene:
    if isinstance(item, Motion):
        return build_scene(item)
    return scene_from_positions(np.asarray(item), fps=fps or 30.0, name=f"motion {k + 1}")


def plot_trajectory(motions_or_positions: Motion | np.ndarray | Sequence, path: str | Path, *,
                    labels: Sequence[str] | None = None, fps: float | None = None,
                    title: str | None = None, dpi: float = 100.0) -> Path:
    """Write a PNG of the root's ground path seen from above, with footsteps.

    Args:
        motions_or_positions: a Motion, a (T, J, 3) array of positions (metres, Y up,
            joint 0 = root) or a list of either.
        path: output .png (written atomically).
        labels: legend entries (default: motion names).
        fps: frame rate of raw position arrays (needed for the foot-speed test).

    Footsteps are runs of frames where a foot is low and slow
    (:func:`motionlang.rendering.scene.contact_frames`); filled markers for the left foot,
    open markers for the right. A circle marks the start, the line ends in an arrow.
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise MotionlangError(f"{path}: a trajectory plot is written as .png")
    items = ([motions_or_positions] if isinstance(motions_or_positions, (Motion, np.ndarray))
             else list(motions_or_positions))
    scenes = [_scene(it, fps, k) for k, it in enumerate(items)]
    labels = list(labels) if labels is not None else [s.name for s in scenes]
    fig, canvas = new_figure(5.0, 5.0, dpi)
    ax = fig.add_subplot(1, 1, 1)
    for k, (s, lab) in enumerate(zip(scenes, labels)):
        c = PATH_COLOURS[k % len(PATH_COLOURS)]
        xy = s.root[:, :2]
        ax.plot(xy[:, 0], xy[:, 1], color=c, lw=1.5, label=lab)
        ax.plot(*xy[0], "o", color=c, ms=6)
        if len(xy) > 1 and np.linalg.norm(xy[-1] - xy[-2]) > 0:
            ax.annotate("", xy=xy[-1], xytext=xy[-2],
                        arrowprops=dict(arrowstyle="-|>", color=c, lw=1.5))
        for foot, pos in footsteps(s):
            first = foot == s.feet[0]
            ax.plot(*pos, marker="s", ms=5, color=c, mfc=c if first else "white", mew=1.0,
                    ls="none")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("-z (m)  (top view)")
    ax.grid(True, color="#e0e0e0", lw=0.5)
    ax.set_title(title or "root trajectory and footsteps", fontsize=10)
    # proxies explain the footstep markers once, whatever the number of paths
    ax.plot([], [], "s", color="#404040", ms=5, label="left foot")
    ax.plot([], [], "s", color="#404040", mfc="white", ms=5, label="right foot")
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, facecolor="white")
    return path

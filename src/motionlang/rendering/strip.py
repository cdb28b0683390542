"""A PNG strip of key poses side by side, the figure moving along the ground (as in the
motion-language papers' figures)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection

from motionlang.errors import MotionlangError
from motionlang.kinematics import Motion
from motionlang.rendering.draw import (
    GRID_COLOUR,
    bone_segments,
    grid_segments,
    new_figure,
    side_legend,
)
from motionlang.rendering.scene import (
    CENTRE,
    LEFT,
    RIGHT,
    SIDE_COLOURS,
    Scene,
    build_scene,
    camera_basis,
    view_azimuth,
)
from motionlang.utils.atomic import atomic_path

POSE_INCHES = 2.2  # drawn height of the body


def strip_layout(root_along: np.ndarray, picks: np.ndarray, gap: float) -> np.ndarray:
    """Extra shift (T,) metres along the travel direction so that the chosen poses stand at
    least ``gap`` apart; a motion in place is spread out, a fast walk keeps its real
    spacing. The shift is interpolated between chosen frames so the path stays continuous.

    Args:
        root_along: (T,) root position along the travel direction, metres.
        picks: (N,) increasing frame indices of the drawn poses.
        gap: minimum spacing, metres.
    """
    along = root_along[picks]
    extra = np.concatenate([[0.0], np.maximum(0.0, gap - np.diff(along))])
    shift_at_picks = np.cumsum(extra)
    return np.interp(np.arange(len(root_along)), picks, shift_at_picks)


def render_strip(motion: Motion | Scene, path: str | Path, n_frames: int = 8, title: str | None = None,
                 *, dpi: float = 100.0) -> Path:
    """Write a PNG with ``n_frames`` evenly spaced poses of ``motion``, left to right.

    The camera looks at the body's side, slightly from the front (orthographic), travel goes to the right; earlier
    poses are fainter, each is labelled with its time, the root's ground path is drawn.

    Returns:
        the path written (atomically).
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise MotionlangError(f"{path}: a pose strip is written as .png, got "
                              f"{path.suffix or '(no extension)'!r}")
    if n_frames < 1:
        raise ValueError(f"n_frames must be >= 1, got {n_frames}")
    scene = motion if isinstance(motion, Scene) else build_scene(motion)
    T = scene.n_frames
    picks = np.unique(np.linspace(0, T - 1, n_frames).round().astype(int))
    fwd3 = np.array([scene.forward[0], scene.forward[1], 0.0])
    shift = strip_layout(scene.root @ fwd3, picks, gap=0.45 * scene.height)
    offsets = shift[:, None] * fwd3  # (T, 3)
    # an orthographic side view drawn in 2-D: exact equal scaling, and the picture's width
    # is exactly the poses' spread
    view = _View(*camera_basis(view_azimuth(scene.forward, front_deg=20.0), elev=8.0))
    ground = scene.root + offsets
    ground[:, 2] = scene.floor
    pad = 0.12 * scene.height
    fig, ax = _strip_axes(scene, picks, offsets, ground, view, pad, title, dpi)
    _draw_floor(ax, scene, ground, view)
    _draw_poses(ax, scene, picks, offsets, ground, view, pad)
    side_legend(fig)
    if title:
        fig.suptitle(title, fontsize=10)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, facecolor="white")
    return path


class _View:
    """An orthographic camera: screen axes ``right``, ``up`` and viewing direction ``eye``
    (each (3,))."""

    def __init__(self, right: np.ndarray, up: np.ndarray, eye: np.ndarray):
        self.right, self.up, self.eye = right, up, eye

    def project(self, p: np.ndarray) -> np.ndarray:
        """(..., 3) world points -> (..., 2) screen coordinates, metres."""
        return np.stack([p @ self.right, p @ self.up], axis=-1)


def _strip_axes(scene: Scene, picks: np.ndarray, offsets: np.ndarray, ground: np.ndarray,
                view: _View, pad: float, title: str | None, dpi: float):
    """(figure, axes) sized so that the body is ``POSE_INCHES`` tall and the picture just
    holds the drawn poses and the ground path."""
    drawn = np.concatenate([scene.points[f] + offsets[f] for f in picks])
    u, v = drawn @ view.right, drawn @ view.up
    x0 = min(u.min(), (ground @ view.right).min()) - pad
    x1 = max(u.max(), (ground @ view.right).max()) + pad
    y0, y1 = (ground @ view.up).min() - 1.6 * pad, v.max() + pad
    height_in = POSE_INCHES * (y1 - y0) / scene.height
    width_in = float(np.clip(height_in * (x1 - x0) / (y1 - y0), 1.5,
                             2.5 * POSE_INCHES * len(picks)))
    title_in = 0.3 if title else 0.0
    fig, _ = new_figure(width_in, height_in + title_in, dpi)  # the canvas stays on fig
    ax = fig.add_axes((0.0, 0.0, 1.0, height_in / (height_in + title_in)))
    ax.set_axis_off()
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="datalim")
    return fig, ax


def _draw_floor(ax, scene: Scene, ground: np.ndarray, view: _View) -> None:
    """The floor grid around the ground path, and the path itself."""
    lo, hi = ground.min(axis=0) - 0.3 * scene.height, ground.max(axis=0) + 0.3 * scene.height
    ax.add_collection(LineCollection(view.project(grid_segments(lo[0], hi[0], lo[1], hi[1],
                                                                scene.floor)),
                                     colors=GRID_COLOUR, linewidths=0.5, zorder=0))
    ax.plot(*view.project(ground).T, color="#808080", lw=1.0, zorder=1)


def _draw_poses(ax, scene: Scene, picks: np.ndarray, offsets: np.ndarray, ground: np.ndarray,
                view: _View, pad: float) -> None:
    """The picked poses, later ones more opaque and on top, each labelled with its time."""
    for k, f in enumerate(picks):
        alpha = 0.45 + 0.55 * (k + 1) / len(picks)
        for side in (CENTRE, LEFT, RIGHT):
            segs = bone_segments(scene, f, side, offsets[f])
            if len(segs) == 0:
                continue
            # nearer bones (larger depth along the eye direction) drawn on top
            depth = float((segs.mean(axis=1) @ view.eye).mean())
            ax.add_collection(LineCollection(view.project(segs), colors=SIDE_COLOURS[side],
                                             linewidths=2.2, alpha=alpha, capstyle="round",
                                             zorder=2 + k + 0.1 * np.tanh(depth)))
        gx, gy = view.project(ground[f])
        ax.text(gx, gy - 0.5 * pad, f"{f / scene.fps:.1f} s", fontsize=7, color="#606060",
                ha="center", va="top")

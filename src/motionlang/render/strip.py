"""A PNG strip of key poses side by side, the figure moving along the ground (as in the
motion-language papers' figures)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection

from motionlang.errors import MotionlangError
from motionlang.kinematics import Motion
from motionlang.render.draw import GRID_COLOUR, bone_segments, grid_segments, new_figure
from motionlang.render.scene import (CENTRE, LEFT, RIGHT, SIDE_COLOURS, Scene, build_scene,
                                     camera_basis, view_azimuth)
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
    right, up, eye = camera_basis(view_azimuth(scene.forward, front_deg=20.0), elev=8.0)
    drawn = np.concatenate([scene.points[f] + offsets[f] for f in picks])
    u, v = drawn @ right, drawn @ up
    ground = scene.root + offsets
    ground[:, 2] = scene.floor
    pad = 0.12 * scene.height
    x0, x1 = min(u.min(), (ground @ right).min()) - pad, max(u.max(), (ground @ right).max()) + pad
    y0, y1 = (ground @ up).min() - 1.6 * pad, v.max() + pad
    height_in = POSE_INCHES * (y1 - y0) / scene.height
    width_in = float(np.clip(height_in * (x1 - x0) / (y1 - y0), 1.5,
                             2.5 * POSE_INCHES * len(picks)))
    title_in = 0.3 if title else 0.0
    fig, canvas = new_figure(width_in, height_in + title_in, dpi)
    ax = fig.add_axes((0.0, 0.0, 1.0, height_in / (height_in + title_in)))
    ax.set_axis_off()
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="datalim")

    def project(p):  # (..., 3) -> (..., 2)
        return np.stack([p @ right, p @ up], axis=-1)

    lo, hi = ground.min(axis=0) - 0.3 * scene.height, ground.max(axis=0) + 0.3 * scene.height
    ax.add_collection(LineCollection(project(grid_segments(lo[0], hi[0], lo[1], hi[1],
                                                           scene.floor)),
                                     colors=GRID_COLOUR, linewidths=0.5, zorder=0))
    ax.plot(*project(ground).T, color="#808080", lw=1.0, zorder=1)
    for k, f in enumerate(picks):
        alpha = 0.45 + 0.55 * (k + 1) / len(picks)
        for side in (CENTRE, LEFT, RIGHT):
            segs = bone_segments(scene, f, side, offsets[f])
            if len(segs) == 0:
                continue
            # nearer bones (larger depth along the eye direction) drawn on top
            depth = float((segs.mean(axis=1) @ eye).mean())
            ax.add_collection(LineCollection(project(segs), colors=SIDE_COLOURS[side],
                                             linewidths=2.2, alpha=alpha, capstyle="round",
                                             zorder=2 + k + 0.1 * np.tanh(depth)))
        gx, gy = project(ground[f])
        ax.text(gx, gy - 0.5 * pad, f"{f / scene.fps:.1f} s", fontsize=7, color="#606060",
                ha="center", va="top")
    if title:
        fig.suptitle(title, fontsize=10)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, facecolor="white")
    return path

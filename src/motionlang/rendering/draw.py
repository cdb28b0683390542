"""Matplotlib drawing of stick figures on 3-D axes, without pyplot's global state.

Figures are built from ``matplotlib.figure.Figure`` with an explicit Agg canvas, so
importing or using this module never changes the backend of a user's program.
"""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import Axes3D  # noqa: F401  (registers the "3d" projection)
from mpl_toolkits.mplot3d.art3d import Line3DCollection

from motionlang.rendering.scene import CENTRE, LEFT, RIGHT, SIDE_COLOURS, Scene

GRID_STEP = 0.5  # metres between ground grid lines
GRID_COLOUR = "#c8c8c8"


def new_figure(width_in: float, height_in: float, dpi: float) -> tuple[Figure, FigureCanvasAgg]:
    """An off-screen figure (inches, dots per inch) and its Agg canvas; no pyplot state."""
    fig = Figure(figsize=(width_in, height_in), dpi=dpi, facecolor="white")
    return fig, FigureCanvasAgg(fig)


def side_legend(fig: Figure) -> None:
    """"left" and "right" in their colours in the picture's upper left corner (placed in
    inches, so that a small GIF and a wide strip alike have room for both), so that whoever
    looks knows which side is which."""
    top = fig.get_figheight() - 0.06
    for x, word, side in ((0.06, "left", LEFT), (0.36, "right", RIGHT)):
        fig.text(x, top, word, color=SIDE_COLOURS[side], fontsize=7, ha="left", va="top",
                 fontweight="bold", transform=fig.dpi_scale_trans)


def grab(canvas: FigureCanvasAgg) -> np.ndarray:
    """(H, W, 3) uint8 RGB image of the canvas."""
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def clean_3d_axes(ax, *, elev: float, azim: float, zoom: float = 1.0, ortho: bool = False,
                  aspect=(1.0, 1.0, 1.0)) -> None:
    """No panes, ticks or labels: only what is drawn. ``aspect`` = the data ranges, so
    one metre is as long on every axis (nothing looks squashed)."""
    ax.set_axis_off()
    ax.view_init(elev=elev, azim=azim)
    ax.set_box_aspect(aspect, zoom=zoom)
    if ortho:
        ax.set_proj_type("ortho")


def grid_segments(x0: float, x1: float, y0: float, y1: float, z: float,
                  step: float = GRID_STEP) -> np.ndarray:
    """(N, 2, 3) ground-grid lines at multiples of ``step`` inside [x0,x1] x [y0,y1]."""
    xs = np.arange(np.ceil(x0 / step), np.floor(x1 / step) + 1) * step
    ys = np.arange(np.ceil(y0 / step), np.floor(y1 / step) + 1) * step
    segs = [[(x, y0, z), (x, y1, z)] for x in xs] + [[(x0, y, z), (x1, y, z)] for y in ys]
    return np.asarray(segs, dtype=float).reshape(-1, 2, 3)


def bone_segments(scene: Scene, frame: int, side: str, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(B, 2, 3) segments of the bones of one side at one frame."""
    p = scene.points[frame] + np.asarray(shift)
    idx = [b for b, s in zip(scene.bones, scene.bone_sides) if s == side]
    if not idx:
        return np.zeros((0, 2, 3))
    pc = np.asarray(idx)
    return np.stack([p[pc[:, 0]], p[pc[:, 1]]], axis=1)


class StickFigure:
    """The artists of one skeleton on one axes: a line collection per body side."""

    def __init__(self, ax, scene: Scene, colours: dict[str, str] = SIDE_COLOURS,
                 linewidth: float = 2.2, alpha: float = 1.0):
        self.scene = scene
        self.lines = {}
        for side in (CENTRE, LEFT, RIGHT):
            self.lines[side] = add_lines(ax, colors=colours[side], linewidths=linewidth,
                                         alpha=alpha, capstyle="round")

    def set_frame(self, frame: int, shift=(0.0, 0.0, 0.0)) -> None:
        for side, coll in self.lines.items():
            coll.set_segments(bone_segments(self.scene, frame, side, shift))


def add_lines(ax, segments: np.ndarray | None = None, **style) -> Line3DCollection:
    """Add a 3-D line collection (segments (N, 2, 3)); empty ones start as one point, since
    mplot3d cannot compute data limits of an empty collection (limits are set by hand)."""
    if segments is None or len(segments) == 0:
        segments = np.zeros((1, 2, 3))
    coll = Line3DCollection(segments, **style)
    ax.add_collection3d(coll)
    return coll


def clipped(points: np.ndarray, x0: float, x1: float, y0: float, y1: float) -> np.ndarray:
    """Copy of (N, 3) points with those outside the xy window set to NaN (a gap in a line);
    mplot3d does not clip to the axes box by itself."""
    out = np.array(points, dtype=float)
    outside = (out[:, 0] < x0) | (out[:, 0] > x1) | (out[:, 1] < y0) | (out[:, 1] > y1)
    out[outside] = np.nan
    return out

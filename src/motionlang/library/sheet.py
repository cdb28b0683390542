"""A contact sheet: the pose strips of several motions stacked in one PNG, each under its
title (the hits of a search, with their file and span).

Each motion is drawn as the 21-joint body (``features.body21``: feet on the floor, facing
one way) rather than its own rig, so that takes of different rigs read alike side by side
and hands or face joints of dense rigs do not clutter the strip."""
from __future__ import annotations

import tempfile
from pathlib import Path

from motionlang.errors import MotionlangError
from motionlang.features.body21 import body21
from motionlang.kinematics.motion import Motion
from motionlang.rendering.scene import kit21_scene
from motionlang.utils.atomic import atomic_path

DPI = 100.0
TITLE_INCHES = 0.3


def contact_sheet(items: list[tuple[str, Motion]], path: str | Path, *, poses: int = 6,
                  title: str | None = None) -> Path:
    """Write one ``.png`` holding a pose strip (``rendering.strip``) of each motion of
    ``items`` (``(title, motion)``, top to bottom); returns the path (written atomically).

    Raises:
        MotionlangError: a path that is not ``.png``, or no motion to draw.
    """
    from matplotlib.image import imread

    from motionlang.rendering.draw import new_figure
    from motionlang.rendering.strip import render_strip
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise MotionlangError(f"{path}: a contact sheet is written as .png")
    if not items:
        raise MotionlangError(f"{path}: no hits to draw")
    with tempfile.TemporaryDirectory() as tmp:
        images = [imread(render_strip(kit21_scene(body21(m), m.fps, m.name),
                                      Path(tmp) / f"{i}.png", n_frames=poses, dpi=DPI))
                  for i, (_, m) in enumerate(items)]
    width = max(im.shape[1] for im in images) / DPI
    heights = [im.shape[0] / DPI + TITLE_INCHES for im in images]
    top = TITLE_INCHES if title else 0.0
    total = sum(heights) + top
    fig, _ = new_figure(width, total, DPI)
    if title:
        fig.suptitle(title, fontsize=11, y=1.0 - 0.2 * TITLE_INCHES / total, va="top")
    y = total - top
    for (label, _), im, h in zip(items, images, heights):
        y -= h
        ax = fig.add_axes((0.0, y / total, im.shape[1] / DPI / width,
                           (h - TITLE_INCHES) / total))
        ax.imshow(im, interpolation="none")
        ax.set_axis_off()
        fig.text(0.01, (y + h - 0.5 * TITLE_INCHES) / total, label, fontsize=9,
                 va="center", ha="left", family="monospace")
    with atomic_path(path) as tmp_png:
        fig.savefig(tmp_png, format="png", dpi=DPI, facecolor="white")
    return path

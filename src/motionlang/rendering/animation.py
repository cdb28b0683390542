"""Animated stick figures: ``render_animation(motion_or_motions, "out.gif" | "out.mp4")``."""
from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.kinematics import Motion
from motionlang.rendering.draw import (
    GRID_COLOUR,
    StickFigure,
    add_lines,
    clean_3d_axes,
    clipped,
    grab,
    grid_segments,
    new_figure,
    side_legend,
)
from motionlang.rendering.scene import (
    SIDE_COLOURS,
    SIDE_COLOURS_ALT,
    Scene,
    build_scene,
    sample_times,
    view_azimuth,
)
from motionlang.utils.atomic import atomic_path
from motionlang.utils.progress import progress

MAX_OUT_FPS = 25.0  # GIF delays are centiseconds: 25 fps = 4 cs is exact
ANIMATION_FORMATS = (".gif", ".mp4")


class _Panel:
    """One 3-D axes showing one motion (or several overlaid) with its own camera."""

    def __init__(self, fig, rect, scenes: list[Scene], camera: str, title: str | None):
        self.scenes = scenes
        ax = fig.add_axes(rect, projection="3d")
        self.ax = ax
        lead = scenes[0]
        self.floor = min(s.floor for s in scenes)
        height = max(s.height for s in scenes)
        roots = np.concatenate([s.root for s in scenes])
        extent = np.ptp(roots[:, :2], axis=0).max()
        # follow the body when it travels further than the view would comfortably hold
        self.follow = camera == "follow" or (camera == "auto" and extent > 1.2 * height)
        self.half = 0.75 * height
        # the box spans 2*half horizontally and ztop vertically; box aspect = data ranges
        self.ztop = 1.15 * height
        if not self.follow:
            pts = np.concatenate([s.points.reshape(-1, 3) for s in scenes])
            lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
            self.centre = (lo + hi) / 2
            self.half = max(self.half, 0.55 * float((hi - lo).max()))
        clean_3d_axes(ax, elev=10.0, azim=view_azimuth(lead.forward), zoom=1.6,
                      aspect=(2 * self.half, 2 * self.half, self.ztop))
        self.grid = add_lines(ax, colors=GRID_COLOUR, linewidths=0.6)
        self.figures, self.past, self.future = [], [], []
        for k, s in enumerate(scenes):
            colours = SIDE_COLOURS if k % 2 == 0 else SIDE_COLOURS_ALT
            # the root's ground trajectory: faint dashes ahead, solid behind
            fut, = ax.plot([], [], [], color=colours["C"], lw=0.8, ls="--", alpha=0.35)
            past, = ax.plot([], [], [], color=colours["C"], lw=1.4, alpha=0.8)
            self.future.append(fut)
            self.past.append(past)
            self.figures.append(StickFigure(ax, s, colours))
        if title:
            ax.set_title(title, fontsize=9, pad=0)
        self.clock = ax.text2D(0.02, 0.02, "", transform=ax.transAxes, fontsize=8,
                               color="#606060")
        if not self.follow:
            self._set_window(self.centre)

    def _set_window(self, centre: np.ndarray) -> tuple[float, float, float, float]:
        h = self.half
        x0, x1, y0, y1 = centre[0] - h, centre[0] + h, centre[1] - h, centre[1] + h
        self.ax.set_xlim(x0, x1)
        self.ax.set_ylim(y0, y1)
        self.ax.set_zlim(self.floor, self.floor + self.ztop)
        self.grid.set_segments(grid_segments(x0, x1, y0, y1, self.floor))
        return x0, x1, y0, y1

    def draw(self, t: float) -> None:
        """Pose every motion at time ``t`` seconds (motions that ended hold their last pose)."""
        frames = [min(int(round(t * s.fps)), s.n_frames - 1) for s in self.scenes]
        if self.follow:
            lead = self.scenes[0]
            window = self._set_window(lead.root[frames[0], :2])
        else:
            h = self.half
            window = (self.centre[0] - h, self.centre[0] + h, self.centre[1] - h,
                      self.centre[1] + h)
        for s, f, fig_, past, fut in zip(self.scenes, frames, self.figures, self.past,
                                         self.future):
            fig_.set_frame(f)
            ground = s.root.copy()
            ground[:, 2] = self.floor
            ahead = clipped(ground[f:], *window)
            behind = clipped(ground[:f + 1], *window)
            fut.set_data_3d(ahead[:, 0], ahead[:, 1], ahead[:, 2])
            past.set_data_3d(behind[:, 0], behind[:, 1], behind[:, 2])
        self.clock.set_text(f"{t:5.2f} s")


def _as_list(motions: Motion | Scene | Sequence[Motion | Scene]) -> list[Motion | Scene]:
    if isinstance(motions, (Motion, Scene)):
        return [motions]
    motions = list(motions)
    if not motions or not all(isinstance(m, (Motion, Scene)) for m in motions):
        raise TypeError("expected a Motion or Scene, or a non-empty list of them")
    return motions


def animation_frames(motions: Motion | Sequence[Motion], *, fps: float | None = None,
                     title: str | None = None, size: tuple[float, float] = (4.0, 4.0),
                     dpi: float = 80.0, camera: str = "auto", layout: str = "side",
                     labels: Sequence[str] | None = None, show_progress: bool | None = None,
                     max_frames: int | None = None) -> tuple[float, int, Iterator[np.ndarray]]:
    """Lay out an animation; its frames are drawn lazily, one at a time.

    Returns:
        (output frame rate in Hz, number of frames, iterator of (H, W, 3) uint8 RGB frames).

    Args:
        motions: one motion or several (e.g. ground truth and generated); Motions or
            Scenes.
        fps: output frame rate; default min(25, source rate).
        size: inches (width, height) of one panel; dpi: pixels per inch.
        camera: ``"follow"`` (window centred on the body), ``"fixed"`` (whole motion in
            view) or ``"auto"`` (follow when the motion travels further than ~1.2 body
            heights).
        layout: ``"side"`` (one panel per motion, side by side) or ``"overlay"`` (all in
            one panel, second colour scheme for every other motion).
        labels: panel titles (default: the motions' names when there are several).
        max_frames: most frames to draw (default ``scene.RENDER_MAX_FRAMES``); more is a
            MotionlangError before anything is drawn.
    """
    motions = _as_list(motions)
    if camera not in ("auto", "follow", "fixed"):
        raise ValueError(f"camera must be 'auto', 'follow' or 'fixed', got {camera!r}")
    if layout not in ("side", "overlay"):
        raise ValueError(f"layout must be 'side' or 'overlay', got {layout!r}")
    src_fps = max(m.fps for m in motions)
    if fps is not None and not fps > 0:
        raise ValueError(f"fps must be positive, got {fps}")
    # at least 1 Hz: a GIF's frame delay is a 16-bit count of centiseconds
    out_fps = float(max(min(fps or MAX_OUT_FPS, src_fps), 1.0))
    duration = max((m.n_frames - 1) / m.fps for m in motions)
    times = sample_times(int(round(duration * src_fps)) + 1, src_fps, out_fps,
                         max_frames) / src_fps   # refused before any work if too many
    # a Scene (e.g. ``scene.kit21_scene`` of a model's joint positions) is drawn as it is;
    # fps, n_frames and name exist on both types
    scenes = [m if isinstance(m, Scene) else build_scene(m) for m in motions]
    groups = [scenes] if layout == "overlay" else [[s] for s in scenes]
    if labels is None:
        labels = [m.name for m in motions] if len(groups) > 1 else [None]
    n = len(groups)
    top = 0.9 if title else 1.0
    fig, canvas = new_figure(size[0] * n, size[1], dpi)
    side_legend(fig)
    if title:
        fig.suptitle(title, fontsize=10)
    panels = [_Panel(fig, (i / n, 0.0, 1.0 / n, top), g, camera, lab)
              for i, (g, lab) in enumerate(zip(groups, list(labels) + [None] * n))]
    disable = None if show_progress is None else not show_progress

    def frames() -> Iterator[np.ndarray]:
        for t in progress(times, desc="rendering", unit="frame", disable=disable):
            for p in panels:
                p.draw(float(t))
            yield grab(canvas)

    return out_fps, len(times), frames()


def _pad16(img: np.ndarray) -> np.ndarray:
    """Pad with white to multiples of 16 pixels (H.264 macro blocks) instead of letting
    the encoder rescale."""
    h, w = img.shape[:2]
    ph, pw = (-h) % 16, (-w) % 16
    if ph or pw:
        img = np.pad(img, ((0, ph), (0, pw), (0, 0)), constant_values=255)
    return img


def render_animation(motions: Motion | Sequence[Motion], path: str | Path, *,
                     fps: float | None = None, title: str | None = None,
                     size: tuple[float, float] = (4.0, 4.0), dpi: float = 80.0,
                     camera: str = "auto", layout: str = "side",
                     labels: Sequence[str] | None = None, max_frames: int | None = None
                     ) -> Path:
    """Render one or several motions as an animated stick figure.

    Args:
        motions: a ``Motion`` or a list (side by side, or overlaid with ``layout="overlay"``).
        path: ``.gif`` (Pillow) or ``.mp4`` (H.264 via imageio-ffmpeg's bundled ffmpeg).
        fps: output frame rate (frames are sampled in real time); default min(25, source).
        title: a heading over the whole figure. size, dpi: inches per panel and resolution.
        camera, layout, labels, max_frames: see :func:`animation_frames`.

    Returns:
        the path written. The file appears only when complete (atomic write).

    Raises:
        MotionlangError: unsupported output extension.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in ANIMATION_FORMATS:
        raise MotionlangError(f"{path}: unsupported animation format {ext or '(none)'!r}; "
                              "use .gif or .mp4")
    out_fps, _, frames = animation_frames(motions, fps=fps, title=title, size=size, dpi=dpi,
                                          camera=camera, layout=layout, labels=labels,
                                          max_frames=max_frames)
    with atomic_path(path) as tmp:
        if ext == ".gif":
            _write_gif(frames, tmp, out_fps)
        else:
            _write_mp4(frames, tmp, out_fps)
    return path


def _write_gif(frames, tmp: Path, fps: float) -> None:
    from PIL import Image

    # quantise frame by frame: a few hundred KB per frame in RGB would add up on long motions
    images = [Image.fromarray(f).quantize(colors=128, dither=Image.Dither.NONE) for f in frames]
    images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                   duration=1000.0 / fps, loop=0, disposal=1)


def _write_mp4(frames, tmp: Path, fps: float) -> None:
    import imageio.v2 as iio

    writer = iio.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                            quality=7, pixelformat="yuv420p", macro_block_size=16,
                            ffmpeg_log_level="quiet")   # its failure is ours to report
    try:
        for f in frames:
            writer.append_data(_pad16(f))
    finally:
        writer.close()

"""Files of the CMU subject-35 experiment: generated or filled-in model frames as ``.npy``,
a motion file on the subject's ASF skeleton, or an animation; fill-ins as plots.

Model frames are (T, 59) ``datasets.cmu35.model_frames`` values; ``data_dir`` is the folder
holding the ``.mat`` files and ``35.asf``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.datasets.cmu35 import Cmu35, model_frames
from motionlang.errors import MotionlangError
from motionlang.evaluation.crbm.plots import plot_fill
from motionlang.evaluation.crbm.reproduce import frames_to_motion
from motionlang.formats import write_motion
from motionlang.utils.atomic import atomic_write

MOTION_EXTENSIONS = (".bvh", ".amc")
RENDER_EXTENSIONS = (".gif", ".mp4")
FRAME_OUTPUTS = ".npy, .bvh, .amc, .gif or .mp4"


def write_frames(frames: np.ndarray, out: str | Path, data: Cmu35, data_dir: str | Path, *,
                 name: str, start_xz: tuple[float, float] = (0.0, 0.0),
                 title: str | None = None, compare: np.ndarray | None = None) -> Path:
    """(T, 59) model frames -> ``out`` by its extension: ``.npy`` (the frames), ``.bvh`` /
    ``.amc`` (a motion starting at ``start_xz`` on the ground, ASF units) or ``.gif`` /
    ``.mp4`` (beside ``compare``, (T, 59) true frames, where given). Atomic."""
    out = Path(out)
    ext = out.suffix.lower()
    if ext == ".npy":
        with atomic_write(out, "wb") as fh:
            np.save(fh, frames)
        return out
    if ext not in MOTION_EXTENSIONS + RENDER_EXTENSIONS:
        raise MotionlangError(f"{out}: output must be {FRAME_OUTPUTS}")
    asf = Path(data_dir) / "35.asf"
    motion = frames_to_motion(frames, data, asf, start_xz=start_xz, name=name)
    if ext in MOTION_EXTENSIONS:
        write_motion(motion, out)
        return out
    from motionlang.rendering.animation import render_animation
    if compare is None:
        return render_animation(motion, out, title=title)
    truth = frames_to_motion(compare, data, asf, start_xz=start_xz, name="true")
    return render_animation([truth, motion], out, title=title, labels=["true", name])


def start_xz(data: Cmu35, trial: str) -> tuple[float, float]:
    """Where a test trial starts on the ground (x, z in ASF units)."""
    return tuple(data.test[trial][0, [0, 2]])


def write_fill(result: dict, out: str | Path, data: Cmu35, data_dir: str | Path, trial: str,
               *, title: str) -> Path:
    """A fill-in of ``trial`` (``reproduce.fill_trial``'s ``result``) -> ``out``: ``.png``,
    the angles plotted (``plots.plot_fill``); else the trial with the CRBM's first fill-in
    in place of the erased channels (unfolded angles), next to the truth where animated."""
    out = Path(out)
    if out.suffix.lower() == ".png":
        return plot_fill(result, out, title=title)
    truth = model_frames(data.test[trial])
    filled = truth.copy()
    dims = result["erased_dims59"]
    filled[:, dims] = result["crbm_model_frames"][0][:, dims]
    return write_frames(filled, out, data, data_dir, name="CRBM fill-in",
                        start_xz=start_xz(data, trial), title=title, compare=truth)


def write_fill_figures(fills: dict, folder: str | Path, data: Cmu35,
                       data_dir: str | Path) -> list[Path]:
    """Figure 4 of the paper for every fill-in of ``reproduce(..., keep_fills=True)``
    (``{(trial, part): result}``): per cell a ``.png`` plot and a ``.gif`` in ``folder``."""
    folder, paths = Path(folder), []
    for (trial, part), res in fills.items():
        slug = f"{trial}_{part.replace(' ', '_')}"
        paths.append(write_fill(res, folder / f"{slug}.png", data, data_dir, trial,
                                title=f"{trial}: {part} erased"))
        paths.append(write_fill(res, folder / f"{slug}.gif", data, data_dir, trial,
                                title=f"{trial}: gap from frame {res['gap_start']}"))
    return paths

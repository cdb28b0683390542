"""A small library the analysis can read: a body that sits down on a seat, one that stands,
and a walk, on the 21-joint body written as BVH; and a hand-made learned side that knows only
"walks" and "stands" ("sits" is half a walk to it), for the search tests and the browser's."""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

import motionlang as ml
from helpers.bodies import FPS, SIT, I, blend, hold, pose, take
from motionlang.features.body21 import body21
from motionlang.library.embedder import Embedder
from motionlang.rendering.output import body_motion

WORDS = {"walks": [1.0, 0.0], "stands": [0.0, 1.0], "sits": [0.7, 0.7], "down": [0.7, 0.7]}


def walking(seconds: float) -> np.ndarray:
    """(T, 21, 3) the standing body carried forward at 1.2 m/s, its feet stepping."""
    t = np.arange(int(seconds * FPS)) / FPS
    p = hold(pose(), seconds).copy()
    p[:, :, 2] += 1.2 * t[:, None]
    swing = 0.25 * np.sin(2 * np.pi * 0.9 * t)
    for foot, sign in (("LA", 1), ("LF", 1), ("LMrot", 1), ("RA", -1), ("RF", -1),
                       ("RMrot", -1)):
        p[:, I[foot], 2] += sign * swing
        p[:, I[foot], 1] += 0.06 * np.clip(sign * np.cos(2 * np.pi * 0.9 * t), 0, None)
    return p


def motion_vector(m) -> np.ndarray:
    """(2,) how far the root travelled a second, and a constant."""
    p = body21(m)[:, 0]
    moved = np.linalg.norm(p[-1, [0, 2]] - p[0, [0, 2]]) / max(len(p) / m.fps, 1e-3)
    return np.array([moved, 0.3])


def text_vector(s: str) -> np.ndarray:
    return np.array(WORDS.get(s.split()[-1], [0.5, 0.5]))


def hand_made() -> Embedder:
    """The learned side (module-level functions: it can be sent to worker processes)."""
    return Embedder("hand-made", "g", text_vector, motion_vector)


def make_library(folder: Path) -> tuple[Path, Path]:
    """(the library folder, its index) made under ``folder``."""
    root = folder / "mocap"
    (root / "chairs").mkdir(parents=True)
    sit = take(hold(pose(), 1.0), blend(pose(), SIT, 1.0), hold(SIT, 2.0),
               blend(SIT, pose(), 1.0), hold(pose(), 1.0))
    for name, p in (("chairs/sit.bvh", sit), ("stand.bvh", hold(pose(), 4.0)),
                    ("walk.bvh", walking(4.0))):
        ml.write_motion(body_motion(p, FPS)[0], root / name)
    out = root.parent / "library.idx"
    ml.index(root, out, hand_made(), show_progress=False)
    return root, out


def dying_motion_vector(m) -> np.ndarray:
    """As :func:`motion_vector`, but the process dies on the walk, as one killed would."""
    if "walk" in str(m.name):
        # a killed process dies a while after its last result went back: the parent reads it
        time.sleep(0.5)
        os._exit(3)
    return motion_vector(m)


def dying() -> Embedder:
    """:func:`hand_made` whose worker process dies on the walk (the same identity)."""
    return Embedder("hand-made", "g", text_vector, dying_motion_vector)

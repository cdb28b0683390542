"""Writing BVH: a Motion read from a BVH file (or one made on that rig, e.g. retargeted
onto it) goes back in the file's own layout; any other Motion in a plain one.

The file's own layout (``meta["bvh_hierarchy"]``, see :mod:`motionlang.formats.bvh`): the
dropped ancestors of a re-rooted Motion come back with their own constant channel values
and the new root's channels carry what is left of its world transform; every joint keeps
its channel list and order (position channels hold the joint's offset), End Sites their
names, OFFSETs their file values where position channels override them. When the Motion no
longer fits that layout (other joints, a rotation its channels cannot express), the plain
layout is written instead.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.formats.bvh_layouts import own_layout, plain_layout
from motionlang.formats.bvh_read import FPS_TOLERANCE
from motionlang.formats.units import resolve_unit
from motionlang.kinematics.motion import Motion
from motionlang.utils.atomic import atomic_write


def _fmt(v: float) -> str:
    """A channel value: 6 decimals (1e-6 degrees, 1e-8 m in cm files), no trailing zeros."""
    s = f"{v:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def write_bvh(motion: Motion, path: str | Path, unit: float | str | None = None) -> None:
    """Write any Motion as a Y-up BVH file that Blender imports.

    A Motion whose ``meta["bvh_hierarchy"]`` still matches its skeleton is written in that
    file layout (module docstring). Otherwise: joints whose rotation already is a BVH
    Euler chain (``pre = post = I``, coordinate DOF axes, ``world = I``) keep their
    channels and angles exactly (3 of them unless the motion came from a BVH); every other
    joint gets ``Zrotation Xrotation Yrotation`` channels from its local rotation
    ``world @ pre @ R(dofs) @ post @ world^T``. Leaf joints without DOFs become End Sites.

    Args:
        unit: metres per written length unit (or ``"m"``, ``"cm"``, ``"mm"``, ``"inch"``);
            default: the skeleton's own unit for BVH-born motions, centimetres otherwise.
    """
    from_bvh = motion.source_format == "bvh"
    hier = motion.meta.get("bvh_hierarchy")
    u = resolve_unit(unit)[1] if unit is not None else \
        motion.skeleton.file_unit if from_bvh or isinstance(hier, dict) else 0.01
    body = own_layout(motion, hier, u) if isinstance(hier, dict) else None
    if body is None:
        body = plain_layout(motion, u, from_bvh)
    header, columns = body
    frame_time = motion.meta.get("frame_time")
    if isinstance(frame_time, float) and (from_bvh or isinstance(hier, dict)) and \
            frame_time > 0 and abs(frame_time * motion.fps - 1) <= FPS_TOLERANCE:
        time_line = f"Frame Time: {frame_time:.10g}"   # the file's own value
    else:
        time_line = f"Frame Time: {1.0 / motion.fps:.8f}"
    data = np.stack(columns, axis=1) if columns else np.zeros((motion.n_frames, 0))
    with atomic_write(path) as fh:
        fh.write("\n".join(header) + "\n")
        fh.write(f"MOTION\nFrames: {motion.n_frames}\n{time_line}\n")
        for row in data:
            fh.write(" ".join(_fmt(v) for v in row) + "\n")



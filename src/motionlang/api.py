"""The Python API under the command line: one call per job, the same defaults as the CLI.

    >>> import motionlang as ml
    >>> m = ml.read_motion("walk.bvh")            # any rig a built-in map (or yours) fits
    >>> ml.describe(m)[0]                         # (sentence, log P), packaged M2L, width 5
    >>> w = ml.generate("a person waves with the right hand")    # Motion, packaged L2M
    >>> ml.write_motion(w, "wave.bvh")            # the 21-joint body, for Blender
    >>> ml.write_motion(ml.generate("a person walks", rig="my_character.bvh"), "walk.bvh")

(``render_motion`` draws a motion; ``motionlang.render`` is the drawing package.)
Packaged models are named ``"m2l"`` and ``"l2m"``; anything else is a checkpoint path.
Generated motions come back as :class:`Motion` objects: on the 21-joint body (joint angles
fitted to the generated positions) or, with ``rig=``, retargeted onto the user's skeleton.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.formats import read_motion, write_motion
from motionlang.kinematics.motion import Motion

PACKAGED = Path(__file__).resolve().parent / "data" / "models"
_KINDS = {"m2l": "m2l", "l2m": "t2m"}


def model_path(name_or_path: str | Path) -> Path:
    """A packaged model's file (``"m2l"``, ``"l2m"``) or the given checkpoint path.

    Raises:
        MotionlangError: no such file.
    """
    path = PACKAGED / f"{name_or_path}.pt" if str(name_or_path) in _KINDS else Path(name_or_path)
    if not path.is_file():
        raise MotionlangError(f"{path}: no such model file")
    return path


def load_model(name_or_path: str | Path, kind: str | None = None):
    """A model in eval mode: the motion-to-language model for ``"m2l"`` (or ``kind="m2l"``),
    a text-to-motion model (L2M or two-stream, by the checkpoint's kind) otherwise."""
    path = model_path(name_or_path)
    kind = kind or _KINDS.get(str(name_or_path), "t2m")
    if kind == "m2l":
        from motionlang.models.seq2seq.m2l import MotionToLanguage
        return MotionToLanguage.load(path)
    from motionlang.decoding.t2m import load_any_t2m
    return load_any_t2m(path)


def read_mapped(path: str | Path, joint_map: dict | str | Path | None = None,
                **kw) -> Motion:
    """``read_motion`` with ``joint_map`` checked against the file's rig at once: a map that
    names joints the rig lacks, misses body joints or is malformed is refused here, naming
    the map file, not later inside a model."""
    motion = read_motion(path, joint_map=joint_map, **kw)
    if joint_map is not None:
        check_map(motion, joint_map)
    return motion


def check_map(motion: Motion, joint_map) -> None:
    """Raise MotionlangError (naming the map) unless ``joint_map`` maps ``motion``'s rig."""
    from motionlang.features.joint_map import as_joint_map, match_rig
    where = joint_map if isinstance(joint_map, (str, Path)) else "joint map"
    try:
        match_rig(motion.skeleton, joint_map=as_joint_map(joint_map))
    except MotionlangError as exc:
        raise MotionlangError(f"{where}: {exc}") from None


def _motion(motion: Motion | str | Path, joint_map) -> Motion:
    if isinstance(motion, Motion):
        if joint_map is not None:
            from motionlang.features.joint_map import as_joint_map
            check_map(motion, joint_map)
            motion = motion.replace(meta={**motion.meta, "joint_map": as_joint_map(joint_map)})
        return motion
    return read_mapped(motion, joint_map)


def load_rig(rig: Motion | str | Path, joint_map: dict | str | Path | None = None) -> Motion:
    """A rig to write generated motions on, checked before anything is generated: its map
    onto the 21-joint body is found and its joints can be aimed (BVH-like rigs with full
    3-axis joints; hinge knees of ASF or MMM skeletons cannot be).

    Raises:
        MotionlangError: naming the rig file and the problem.
    """
    from motionlang.features.joint_map import kit21_weights, positions21
    from motionlang.kinematics.retarget import retarget
    where = rig if isinstance(rig, (str, Path)) else rig.meta.get("path", rig.name)
    motion = _motion(rig, joint_map)
    try:
        W = kit21_weights(motion.skeleton, joint_map=motion.meta.get("joint_map"))[1]
        retarget(positions21(motion[:1]), motion.fps, motion, weights=W)  # one-frame trial
    except MotionlangError as exc:
        raise MotionlangError(f"rig {where}: {exc}") from None
    return motion


def first_frame(model, start: Motion | str | Path,
                joint_map: dict | str | Path | None = None) -> np.ndarray:
    """(F,) model features of the first pose of ``start`` (a Motion or file), for L2M models
    to begin their motions with."""
    from motionlang.features.frames import motion_frames
    if getattr(model, "kind", None) != "l2m":
        raise MotionlangError("a start pose applies to L2M models")
    return motion_frames(model.features, _motion(start, joint_map), 1)[0][0]


def describe(motion: Motion | str | Path, model: Any = None, width: int = 5, *,
             joint_map: dict | str | Path | None = None,
             length_penalty: float = 0.0) -> list[tuple[str, float]]:
    """Sentences for a motion (a Motion or a file), best first: ``[(text, log P), ...]``.

    model: a loaded M2L, a checkpoint path, or None for the packaged one. width: beam width
    and number of sentences (as ``motionlang describe -w``)."""
    from motionlang.decoding.seq2seq import describe as beam_describe
    if width < 1:
        raise MotionlangError(f"width must be >= 1, got {width}")
    if model is None or isinstance(model, (str, Path)):
        model = load_model(model or "m2l", kind="m2l")
    return beam_describe(model, _motion(motion, joint_map), width=width,
                         length_penalty=length_penalty)


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
    from motionlang.features.joint_map import (KIT21_NAMES, KIT21_PARENTS, kit21_weights,
                                               positions21)
    if isinstance(result, Motion):
        if rig is None:
            return result, np.zeros((result.n_frames, len(KIT21_NAMES)))
        fps, result = result.fps, positions21(result)
    if rig is None:
        from motionlang.kinematics.from_positions import motion_from_positions
        motion = motion_from_positions(result, fps, KIT21_NAMES, KIT21_PARENTS, name=name)
        W = np.eye(len(KIT21_NAMES))
    else:
        from motionlang.kinematics.retarget import retarget
        W = kit21_weights(rig.skeleton, joint_map=rig.meta.get("joint_map"))[1]
        motion = retarget(result, fps, rig, weights=W, name=name)
    err = np.linalg.norm(np.einsum("kj,tjc->tkc", W, motion.positions()) - result, axis=-1)
    return motion, err


def generate(text: str, model: Any = None, *, width: int = 5, method: str | None = None,
             seed: int = 0, max_frames: int | None = None,
             rig: Motion | str | Path | None = None,
             start_from: Motion | str | Path | None = None,
             joint_map: dict | str | Path | None = None,
             rig_joint_map: dict | str | Path | None = None) -> Motion:
    """A motion for ``text`` (the best of ``width`` hypotheses), as a :class:`Motion`.

    model: a loaded text-to-motion model, a checkpoint path, or None for the packaged L2M.
    method: None for the model's own way (as ``motionlang generate``: ancestral sampling,
    or mean decoding for models trained on their expected frames), else "sample", "beam"
    or "mean". rig: a Motion or motion file whose skeleton the result is retargeted onto.
    start_from: a Motion or file whose first pose begins the motion (L2M models).
    joint_map / rig_joint_map: how ``start_from`` / ``rig`` map onto the 21-joint body,
    if no built-in map fits them.
    """
    from motionlang.decoding.t2m import default_method, generate_any, output_fps
    if model is None or isinstance(model, (str, Path)):
        model = load_model(model or "l2m")
    rig_motion = None if rig is None else load_rig(rig, rig_joint_map)
    kw: dict[str, Any] = {}
    if start_from is not None:
        kw["first_frame"] = first_frame(model, start_from, joint_map)
    hyps = generate_any(model, text, width=width, method=method or default_method(model),
                        seed=seed, max_frames=max_frames, min_frames=5, **kw)
    return body_motion(hyps[0][0], output_fps(model), rig_motion)[0]


def body21(motion: Motion | str | Path, *, joint_map: dict | str | Path | None = None,
           stature: float | None = None) -> np.ndarray:
    """Any motion (or file) -> (T, 21, 3) metres on the common 21-joint body: feet on the
    floor, frame 0 at the origin facing +Z, scaled to ``stature`` metres if given."""
    from motionlang.features.body21 import body21 as _body21
    return _body21(_motion(motion, joint_map), stature=stature)


def retarget(motion: Motion | str | Path, rig: Motion | str | Path, *,
             joint_map: dict | str | Path | None = None,
             rig_joint_map: dict | str | Path | None = None) -> Motion:
    """``motion`` (any rig) moved onto ``rig``'s skeleton through the 21-joint body."""
    from motionlang.features.joint_map import positions21
    src = _motion(motion, joint_map)
    return body_motion(positions21(src), src.fps, load_rig(rig, rig_joint_map),
                       name=src.name)[0]


def render_motion(motion: Motion | str | Path, path: str | Path, *, title: str | None = None,
                  joint_map: dict | str | Path | None = None) -> Path:
    """Draw a motion: ``.gif`` / ``.mp4`` animation or ``.png`` pose strip."""
    from motionlang.render import render_animation, render_strip
    m = _motion(motion, joint_map)
    if Path(path).suffix.lower() == ".png":
        return render_strip(m, path, title=title or m.name)
    return render_animation(m, path, title=title or m.name)


__all__ = ["read_motion", "write_motion", "read_mapped", "load_model", "describe",
           "generate", "body21", "retarget", "render_motion", "body_motion", "load_rig",
           "first_frame", "check_map", "model_path"]

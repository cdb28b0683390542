"""Motion file formats: read and write by file extension.

* ``.xml`` — KIT MMM (:mod:`motionlang.formats.mmm`)
* ``.bvh`` — Biovision hierarchy (:mod:`motionlang.formats.bvh`)
* ``.amc`` — Acclaim motion with its ``.asf`` skeleton (:mod:`motionlang.formats.asf_amc`)
* ``.mat`` — the MIT walking data as Taylor distributed it (:mod:`motionlang.formats.mit`;
  read only, one sequence at a time)
"""
from __future__ import annotations

from pathlib import Path

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.skeleton import Skeleton

READ_EXTENSIONS = (".xml", ".bvh", ".amc", ".mat")
WRITE_EXTENSIONS = (".bvh", ".xml", ".amc")


def find_asf(amc_path: str | Path) -> Path:
    """The skeleton of ``<subject>_<trial>.amc``: ``<subject>.asf`` next to it, else the only
    ``.asf`` in its folder.

    Raises:
        MotionFormatError: if no single ASF can be chosen.
    """
    amc_path = Path(amc_path)
    folder = amc_path.parent
    subject = amc_path.stem.split("_")[0]
    for cand in (folder / f"{subject}.asf", folder / f"{subject}.ASF"):
        if cand.is_file():
            return cand
    found = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".asf") \
        if folder.is_dir() else []
    if len(found) == 1:
        return found[0]
    why = "none" if not found else f"{len(found)} ({', '.join(p.name for p in found[:4])})"
    raise MotionFormatError(amc_path, f"cannot choose the ASF skeleton: no {subject}.asf and "
                                      f"{why} .asf files in {folder}; pass skeleton=")


def read_motion(path: str | Path, *, skeleton: Skeleton | str | Path | None = None,
                fps: float | None = None, sequence: int = 1) -> Motion:
    """Read a motion file, choosing the reader from the extension.

    Args:
        path: ``.xml`` (MMM), ``.bvh``, ``.amc`` or ``.mat`` (MIT walking data).
        skeleton: for ``.amc``: a ``Skeleton`` or the path of its ``.asf`` (found next to
            the AMC when omitted).
        fps: for ``.amc`` (default 120); for other formats, the motion is resampled to
            ``fps`` if given.
        sequence: for ``.mat`` files holding several sequences: which one (1-based).

    Raises:
        MotionFormatError: missing file, unknown extension, malformed content, or a
            ``sequence`` the file does not hold.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in READ_EXTENSIONS:
        raise MotionFormatError(path, f"unknown motion file extension {ext or '(none)'!r}; "
                                      f"expected one of {', '.join(READ_EXTENSIONS)}")
    if not path.is_file():
        raise MotionFormatError(path, "file not found")
    if ext == ".amc":
        from motionlang.formats.asf_amc import read_amc, read_asf
        if skeleton is None:
            skeleton = find_asf(path)
        if not isinstance(skeleton, Skeleton):
            skeleton = read_asf(skeleton)
        return read_amc(path, skeleton, fps=120.0 if fps is None else fps)
    if ext == ".bvh":
        from motionlang.formats.bvh import read_bvh
        motion = read_bvh(path)
    elif ext == ".mat":
        from motionlang.formats.mit import read_mit
        motions = read_mit(path)
        if not 1 <= sequence <= len(motions):
            raise MotionFormatError(path, f"no sequence {sequence}: the file holds "
                                          f"{len(motions)} (1..{len(motions)})")
        motion = motions[sequence - 1]
    else:
        from motionlang.formats.mmm import read_mmm  # imported lazily: a sibling module
        motion = read_mmm(path)
    if fps is not None and abs(fps - motion.fps) > 1e-9:
        motion = motion.resample(fps)
    return motion


def write_motion(motion: Motion, path: str | Path) -> None:
    """Write ``motion``, choosing the writer from the extension.

    ``.bvh`` accepts any motion; ``.xml`` needs an MMM skeleton and ``.amc`` an ASF one.

    Raises:
        MotionFormatError: unknown extension or a skeleton the format cannot hold.
    """
    path = Path(path)
    ext = path.suffix.lower()
    try:
        if ext == ".bvh":
            from motionlang.formats.bvh import write_bvh
            write_bvh(motion, path)
        elif ext == ".amc":
            from motionlang.formats.asf_amc import write_amc
            write_amc(motion, path)
        elif ext == ".xml":
            if not str(motion.skeleton.name).startswith("mmm"):
                raise MotionFormatError(path, f"MMM XML needs an MMM skeleton, not "
                                              f"{motion.skeleton.name!r}; write .bvh instead")
            from motionlang.formats.mmm import write_mmm
            write_mmm(motion, path)
        else:
            raise MotionFormatError(path, f"cannot write {ext or '(no extension)'!r}; "
                                          f"expected one of {', '.join(WRITE_EXTENSIONS)}")
    except SkeletonError as exc:
        raise MotionFormatError(path, str(exc)) from None


def motion_info(motion: Motion) -> dict:
    """A JSON-friendly summary of a motion.

    Keys: ``name``, ``frames``, ``fps``, ``duration_s``, ``joints`` / ``joint_names`` (the
    joints that carry rotation DOFs: 44 for MMM, where each revolute axis is a joint),
    ``dofs`` (joint DOFs, without the root's translation and rotation), ``nodes`` /
    ``node_names`` (every node of the skeleton tree, fixed segments and end sites included),
    ``source_format``, ``skeleton``.
    """
    sk = motion.skeleton
    moving = [j.name for j in sk.joints if len(j.dof_names)]
    return {"name": motion.name, "frames": motion.n_frames, "fps": float(motion.fps),
            "duration_s": float(motion.duration), "joints": len(moving),
            "joint_names": moving, "dofs": int(sk.ndof), "nodes": len(sk),
            "node_names": list(sk.names), "source_format": motion.source_format,
            "skeleton": sk.name}


__all__ = ["read_motion", "write_motion", "motion_info", "find_asf"]

"""Motion file formats: read and write by file extension.

* ``.xml`` — KIT MMM (:mod:`motionlang.formats.mmm`)
* ``.bvh`` — Biovision hierarchy (:mod:`motionlang.formats.bvh`)
* ``.amc`` — Acclaim motion with its ``.asf`` skeleton (:mod:`motionlang.formats.asf_amc`)
* ``.glb`` / ``.gltf`` — glTF 2.0 skeletal animation with a skinned stick mesh
  (:mod:`motionlang.formats.gltf`; write only, :mod:`motionlang.formats.gltf_read` plays a
  file back as node positions)
* ``.mat`` — the MIT walking data as Taylor distributed it (:mod:`motionlang.formats.mit`;
  read only, one sequence at a time), through a strict MAT-file reader of our own
  (:mod:`motionlang.formats.matfile`: scipy's can be crashed by a crafted file)
* ``.txt`` — a DeepMimic clip of its humanoid3d character, JSON with a ``"Frames"`` list
  (:mod:`motionlang.formats.deepmimic`; read only). Known by its content: a folder scan
  (:func:`is_motion_file`) takes a ``.txt`` file only when it starts as such a clip does.

Every reader turns a bad file into one :class:`MotionFormatError` naming the file (and the
line or frame), never another exception, and checks what a file asks for (size, joints,
frames, memory) against :mod:`motionlang.utils.limits` before asking the system for it.
``benchmarks/fuzzing/`` (outside the package) holds the fuzzing that checks this.
"""
from __future__ import annotations

from pathlib import Path

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.formats.asf_amc import read_amc, read_asf, write_amc
from motionlang.formats.bvh import read_bvh, write_bvh
from motionlang.formats.deepmimic import looks_like_deepmimic, read_deepmimic
from motionlang.formats.gltf import write_gltf
from motionlang.formats.gltf_read import read_gltf
from motionlang.formats.mit import read_mit
from motionlang.formats.mmm import read_mmm, write_mmm
from motionlang.formats.units import motion_stature, unit_name
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.reference_pose import leading_reference_frames
from motionlang.kinematics.skeleton import Skeleton
from motionlang.utils.sidecar import load_json

READ_EXTENSIONS = (".xml", ".bvh", ".amc", ".mat", ".glb", ".gltf")
#: extensions read when the content is a motion's: DeepMimic clips are ``.txt`` files
CONTENT_EXTENSIONS = (".txt",)
WRITE_EXTENSIONS = (".bvh", ".xml", ".amc", ".glb", ".gltf")


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
                                      f"{why} .asf files in {folder}; name it (--asf FILE, "
                                      f"or skeleton= in Python)")


def is_motion_file(path: str | Path) -> bool:
    """Whether a folder scan takes ``path``: an extension of :data:`READ_EXTENSIONS`, or a
    ``.txt`` file that starts as a DeepMimic clip does."""
    ext = Path(path).suffix.lower()
    if ext in READ_EXTENSIONS:
        return True
    return ext in CONTENT_EXTENSIONS and looks_like_deepmimic(path)


def read_joint_map(path: str | Path) -> dict:
    """A user's joint map file (JSON; format in ``motionlang.features.joint_map``), parsed
    but not yet checked against a skeleton.

    Raises:
        MotionlangError: the file is missing, not a regular file, too big, not JSON
            within the bounds of :mod:`motionlang.utils.sidecar`, or not a JSON object.
    """

    path = Path(path)
    spec = load_json(path, "joint map")   # a regular file, bounded; one line naming it
    if not isinstance(spec, dict):
        raise MotionFormatError(path, "joint map must be a JSON object")
    spec.setdefault("name", path.stem)
    spec.setdefault("path", str(path))
    return spec


def read_motion(path: str | Path, *, skeleton: Skeleton | str | Path | None = None,
                fps: float | None = None, sequence: int = 1,
                joint_map: dict | str | Path | None = None) -> Motion:
    """Read a motion file, choosing the reader from the extension.

    Args:
        path: ``.xml`` (MMM), ``.bvh``, ``.amc``, ``.mat`` (MIT walking data), ``.txt``
            (a DeepMimic clip) or ``.glb`` / ``.gltf`` (a skeletal animation: joint angles
            fitted to its joints' positions).
        skeleton: for ``.amc``: a ``Skeleton`` or the path of its ``.asf`` (found next to
            the AMC when omitted).
        fps: for ``.amc`` (default 120); for other formats, the motion is resampled to
            ``fps`` if given.
        sequence: for ``.mat`` files holding several sequences: which one (1-based).
        joint_map: how this rig maps onto the 21-joint body, for rigs no built-in map
            recognises: a map dict or the path of its JSON file (``motionlang rig template``
            writes one). Kept in ``meta["joint_map"]``, so it follows the motion into
            every feature, model and command.

    Raises:
        MotionFormatError: missing file, unknown extension, malformed content, or a
            ``sequence`` the file does not hold.
    """
    path = Path(path)
    if joint_map is not None:
        spec = joint_map if isinstance(joint_map, dict) else read_joint_map(joint_map)
        motion = read_motion(path, skeleton=skeleton, fps=fps, sequence=sequence)
        motion.meta["joint_map"] = spec
        return motion
    ext = path.suffix.lower()
    if ext not in READ_EXTENSIONS + CONTENT_EXTENSIONS:
        raise MotionFormatError(path, f"unknown motion file extension {ext or '(none)'!r}; "
                                      f"expected one of {', '.join(READ_EXTENSIONS)} or .txt "
                                      "(DeepMimic)")
    if not path.is_file():
        raise MotionFormatError(path, "not a regular file (a FIFO, device or socket)"
                                if path.exists() else "file not found")
    if ext == ".amc":
        if skeleton is None:
            skeleton = find_asf(path)
        if not isinstance(skeleton, Skeleton):
            skeleton = read_asf(skeleton)
        return read_amc(path, skeleton, fps=120.0 if fps is None else fps)
    if ext == ".bvh":
        motion = read_bvh(path)
        lead = leading_reference_frames(motion)
        if lead:   # an exporter's T-pose and its blend into the take: not the subject's
            motion = motion[lead:]
            motion.meta["reference_frames"] = lead
    elif ext == ".txt":
        motion = read_deepmimic(path)
    elif ext in (".glb", ".gltf"):
        motion = read_gltf(path)
    elif ext == ".mat":
        motions = read_mit(path)
        if not 1 <= sequence <= len(motions):
            raise MotionFormatError(path, f"no sequence {sequence}: the file holds "
                                          f"{len(motions)} (1..{len(motions)})")
        motion = motions[sequence - 1]
    else:
        motion = read_mmm(path)
    if fps is not None and abs(fps - motion.fps) > 1e-9:
        motion = motion.resample(fps)
    return motion


def write_motion(motion: Motion, path: str | Path) -> Path:
    """Write ``motion``, choosing the writer from the extension; returns the path.

    ``.bvh``, ``.glb`` and ``.gltf`` accept any motion; ``.xml`` needs an MMM skeleton and
    ``.amc`` an ASF one.

    Raises:
        MotionFormatError: unknown extension or a skeleton the format cannot hold.
    """
    path = Path(path)
    ext = path.suffix.lower()
    try:
        if ext == ".bvh":
            write_bvh(motion, path)
        elif ext in (".glb", ".gltf"):
            write_gltf(motion, path)
        elif ext == ".amc":
            write_amc(motion, path)
        elif ext == ".xml":
            if not str(motion.skeleton.name).startswith("mmm"):
                raise MotionFormatError(path, f"MMM XML needs an MMM skeleton, not "
                                              f"{motion.skeleton.name!r}; write .bvh instead")
            write_mmm(motion, path)
        else:
            raise MotionFormatError(path, f"cannot write {ext or '(no extension)'!r}; "
                                          f"expected one of {', '.join(WRITE_EXTENSIONS)}")
    except SkeletonError as exc:
        raise MotionFormatError(path, str(exc)) from None
    return path


def motion_info(motion: Motion) -> dict:
    """A JSON-friendly summary of a motion.

    Keys: ``name``, ``frames``, ``fps``, ``duration_s``, ``joints`` / ``joint_names`` (the
    joints that carry rotation DOFs: 44 for MMM, where each revolute axis is a joint),
    ``dofs`` (joint DOFs, without the root's translation and rotation), ``nodes`` /
    ``node_names`` (every node of the skeleton tree, fixed segments and end sites included),
    ``source_format``, ``skeleton``, ``unit`` (the file's length unit: what a BVH reader
    decided, e.g. ``"cm"`` or ``"BVH units"``, else the one the format defines: ``"mm"``
    for MMM, ``"1/0.45 inch"`` for a CMU ASF), ``stature_m`` (the body's stature in metres,
    :func:`motionlang.formats.units.estimate_stature`), ``declared_fps`` where the
    motion is read at another rate than its header's (``analysis.rate``; None else), and
    ``reference_frames``: the frames of an exporter's T-pose left out at the start
    (``kinematics.reference_pose``; 0 where none).
    """

    sk = motion.skeleton
    moving = [j.name for j in sk.joints if len(j.dof_names)]
    unit = motion.meta.get("unit") if motion.source_format == "bvh" else None
    stature = motion.meta.get("stature_m") if motion.source_format == "bvh" else None
    return {"name": motion.name, "frames": motion.n_frames, "fps": float(motion.fps),
            "duration_s": float(motion.duration), "joints": len(moving),
            "joint_names": moving, "dofs": int(sk.ndof), "nodes": len(sk),
            "node_names": list(sk.names), "source_format": motion.source_format,
            "skeleton": sk.name, "unit": str(unit or unit_name(sk.file_unit)),
            "stature_m": float(stature if stature is not None else motion_stature(motion)),
            "declared_fps": motion.meta.get("declared_fps"),
            "reference_frames": int(motion.meta.get("reference_frames", 0))}


def info_text(info: dict) -> str:
    """A :func:`motion_info` (with its ``path``) as ``motionlang info`` prints it."""
    names = info["joint_names"]
    shown = ", ".join(names[:8]) + (f", ... ({len(names)} in all)" if len(names) > 8 else "")
    return "\n".join([
        f"{info['path']}",
        f"  format    {info['source_format']}  (skeleton {info.get('skeleton', '?')})",
        f"  frames    {info['frames']} at {info['fps']:g} Hz = {info['duration_s']:.2f} s"
        + (f" (its header says {info['declared_fps']:g} Hz)"
           if info.get("declared_fps") is not None else "")
        + (f"; the {info['reference_frames']} frames before them, the rig's T-pose and the "
           "exporter's blend out of it, left out" if info.get("reference_frames") else ""),
        f"  joints    {info['joints']} with {info['dofs']} DOFs (+ root), "
        f"{info['nodes']} skeleton nodes",
        f"  body      {info['stature_m']:.2f} m tall; lengths in {info['unit']}",
        f"  names     {shown}"])


__all__ = ["read_motion", "write_motion", "motion_info", "info_text", "find_asf",
           "is_motion_file", "read_joint_map"]

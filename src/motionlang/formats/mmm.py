"""KIT MMM motion XML (the format of the KIT Motion-Language dataset).

A file holds one or more ``<Motion>`` elements; the first one with a ``<JointOrder>`` is
the human (others animate objects). Per frame: ``Timestep`` (s), ``RootPosition`` (mm,
source frame Z up), ``RootRotation`` (roll, pitch, yaw radians - see
:mod:`motionlang.formats.mmm_model`) and ``JointPosition`` (radians, one value per
``JointOrder`` entry). The subject's height (``ModelProcessorConfig/Height``, m) scales
the reference model.
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from xml.parsers import expat
from xml.sax.saxutils import escape

import numpy as np

from motionlang.errors import MotionFormatError, SkeletonError
from motionlang.formats.mmm_model import MMM_DOF_ORDER, mmm_height, mmm_skeleton
from motionlang.kinematics.motion import Motion
from motionlang.utils import limits
from motionlang.utils.atomic import atomic_write

__all__ = ["MMM_DOF_ORDER", "mmm_skeleton", "read_mmm", "write_mmm"]

DEFAULT_HEIGHT_M = 1.75
DEFAULT_FPS = 100.0  # KIT records at 100 Hz; used when a file has a single frame
PARSE_FACTOR = 10    # memory of the element tree and its texts per byte of file


def _frame_line(text: bytes, frame: int) -> int | None:
    """1-based line of the ``frame``-th ``<MotionFrame>`` (only computed on error)."""
    for i, m in enumerate(re.finditer(rb"<MotionFrame\b", text)):
        if i == frame:
            return text.count(b"\n", 0, m.start()) + 1
    return None


_FIELDS = ("Timestep", "RootPosition", "RootRotation", "JointPosition")


def _frame_values(frames: list[ET.Element], n_dof: int, fail) -> np.ndarray:
    """(T, 7 + n_dof) floats: Timestep, RootPosition (3), RootRotation (3), JointPosition.

    Tokens of all frames are converted in one numpy call (reading is hot in the corpus
    tools); only on failure is the offending frame and field looked up.
    """
    sizes = (1, 3, 3, n_dof)
    tokens: list[str] = []
    for f, frame in enumerate(frames):
        for tag, n in zip(_FIELDS, sizes):
            el = frame.find(tag)
            if el is None:
                if n == 0:
                    continue
                fail(f, f"missing <{tag}>")
            toks = (el.text or "").split()
            if len(toks) != n:
                fail(f, f"<{tag}> has {len(toks)} values, expected {n}")
            tokens.extend(toks)
    width = sum(sizes)
    try:
        arr = np.array(tokens, dtype=float).reshape(len(frames), width)
    except ValueError:
        i = next(i for i, t in enumerate(tokens) if not _is_float(t))
        fail(i // width, f"malformed number {tokens[i]!r} in <{_field_at(i % width, sizes)}>")
    bad = ~np.isfinite(arr)
    if bad.any():
        f, c = np.argwhere(bad)[0]
        fail(int(f), f"non-finite value (NaN or inf) in <{_field_at(int(c), sizes)}>")
    return arr


def _field_at(column: int, sizes) -> str:
    for tag, n in zip(_FIELDS, sizes):
        if column < n:
            return tag
        column -= n
    return _FIELDS[-1]


def _is_float(token: str) -> bool:
    try:
        float(token)
        return True
    except ValueError:
        return False


class _Stop(Exception):
    """Internal: the prolog ends where the root element starts."""


def _check_prolog(text: bytes, path) -> None:
    """Refuse a document type declaration and an encoding expat cannot read, parsing only
    up to the root element.

    No MMM file has a DTD, and a DTD is what XML bombs need (entities expanding a
    billionfold, external entities reading local files or URLs). expat already refuses
    those (amplification limit; ElementTree resolves no external entity); refusing every
    DTD keeps it so whatever the next trick is. Works in any encoding the file declares.
    """
    parser = expat.ParserCreate()

    def doctype(name, *_):
        raise MotionFormatError(path, f"document type declaration <!DOCTYPE {name}> not "
                                      "allowed (MMM files have none; entities are refused)")

    def stop(*_):
        raise _Stop

    parser.StartDoctypeDeclHandler = doctype
    parser.StartElementHandler = stop
    try:
        parser.Parse(text, True)
    except _Stop:
        return
    except expat.ExpatError as exc:
        raise MotionFormatError(path, f"invalid XML: {expat.ErrorString(exc.code)}",
                                line=exc.lineno) from None
    except (ValueError, LookupError) as exc:  # 'utf-32' / unknown encoding declared
        raise MotionFormatError(path, f"cannot read the declared encoding ({exc})") from None


def _config_value(motion: ET.Element, tag: str, default: float, path) -> float:
    el = motion.find(f"ModelProcessorConfig/{tag}")
    if el is None or not (el.text or "").strip():
        return default
    try:
        value = float(el.text)
    except ValueError:
        raise MotionFormatError(path, f"malformed <{tag}> {el.text.strip()!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise MotionFormatError(path, f"<{tag}> must be positive, got {value}")
    return value


def read_mmm(path: str | Path) -> Motion:
    """Read a KIT MMM motion file into a :class:`Motion` on :func:`mmm_skeleton`.

    DOFs missing from ``<JointOrder>`` stay 0; a file without ``<Height>`` gets a 1.75 m
    subject. ``meta``: ``height`` (m), ``mass`` (kg or None), ``path``, ``subject`` (the
    ``<Motion name>``).

    Raises:
        MotionFormatError: unreadable XML (an encoding that cannot be read, a DTD), no
            JointOrder, an unknown joint name, no frames, a frame with a malformed number,
            a wrong value count or NaN (file, line and frame index named), or a file or
            motion beyond the limits (``utils.limits``).
    """
    path = Path(path)
    text, root = _parse_xml(path)
    motion = _human_motion(root, path)
    order = [j.get("name") for j in motion.find("JointOrder").findall("Joint")]
    height = _config_value(motion, "Height", DEFAULT_HEIGHT_M, path)
    mass_el = motion.find("ModelProcessorConfig/Mass")
    mass = _config_value(motion, "Mass", 0.0, path) if mass_el is not None else None
    skeleton = mmm_skeleton(height)
    names = skeleton.dof_names
    col = {n: i for i, n in enumerate(names)}
    _check_joint_order(order, col, path)
    frames = motion.findall("MotionFrames/MotionFrame")
    if not frames:
        raise MotionFormatError(path, "motion has no frames")
    T = len(frames)
    limits.check_motion(path, T, len(skeleton), 7 + len(order))

    def fail(frame: int, msg: str):
        raise MotionFormatError(path, msg, line=_frame_line(text, frame), frame=frame)

    arr = _frame_values(frames, len(order), fail)
    times, trans, rpy, values = arr[:, 0], arr[:, 1:4], arr[:, 4:7], arr[:, 7:]
    fps = _frame_rate(times, path)
    angles = np.zeros((T, len(names)))
    angles[:, [col[n] for n in order]] = values
    return Motion(skeleton, fps, trans * skeleton.file_unit, rpy[:, ::-1].copy(), angles,
                  name=path.stem, source_format="mmm",
                  meta={"height": height, "mass": mass, "path": str(path),
                        "subject": motion.get("name")})


def _parse_xml(path: Path) -> tuple[bytes, ET.Element]:
    """The file's bytes and its element tree, refusing DTDs and unreadable encodings."""
    limits.check_file(path, PARSE_FACTOR)
    try:
        text = path.read_bytes()  # bytes: expat then honours the file's declared encoding
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    _check_prolog(text, path)
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        line, _col = exc.position
        raise MotionFormatError(path, f"invalid XML: {exc}", line=line) from None
    except (ValueError, LookupError) as exc:  # in case the prolog check let one through
        raise MotionFormatError(path, f"cannot read the declared encoding ({exc})") from None
    return text, root


def _human_motion(root: ET.Element, path) -> ET.Element:
    """The ``<Motion>`` of the human: the one on the model "mmm.xml", else the first with a
    ``<JointOrder>`` (a file may also animate objects)."""
    candidates = [m for m in root.iter("Motion") if m.find("JointOrder") is not None]
    if not candidates:
        raise MotionFormatError(path, "no <Motion> with a <JointOrder> found")
    return next((m for m in candidates
                 if (m.findtext("Model/File") or "").strip().lower().endswith("mmm.xml")),
                candidates[0])


def _check_joint_order(order: list, col: dict[str, int], path) -> None:
    """Every ``<JointOrder>`` name a DOF of the model, none twice."""
    unknown = [n for n in order if n not in col]
    if unknown:
        raise MotionFormatError(path, f"unknown joint name {unknown[0]!r} in <JointOrder> "
                                      f"(the MMM model has {len(col)} DOFs)")
    if len(set(order)) != len(order):
        raise MotionFormatError(path, "a joint appears twice in <JointOrder>")


def _frame_rate(times: np.ndarray, path) -> float:
    """Frames per second from the timesteps (T,) s; ``DEFAULT_FPS`` for a single frame."""
    if len(times) <= 1:
        return DEFAULT_FPS
    dt = float(np.median(np.diff(times)))
    if not dt > 0:
        raise MotionFormatError(path, "timesteps do not increase")
    fps = 1.0 / dt
    if abs(fps - round(fps)) < 1e-3 * fps:  # 0.01 s steps printed as 0.01 -> 100 Hz
        fps = float(round(fps))
    return fps


_HEAD = """<?xml version='1.0'?>
<MMM>
\t<Motion name='{name}'>
\t\t<Model>
\t\t\t<File>mmm.xml</File>
\t\t</Model>
\t\t<ModelProcessorConfig type='Winter'>
\t\t\t<Height>{height:.6g}</Height>
{mass}\t\t</ModelProcessorConfig>
\t\t<JointOrder>
{joints}\t\t</JointOrder>
\t\t<MotionFrames>
"""
_TAIL = "\t\t</MotionFrames>\n\t</Motion>\n\n</MMM>\n"


def _frame_template(n_dof: int) -> str:
    zeros = "0 " * n_dof
    return ("\t\t\t<MotionFrame>\n\t\t\t\t<Timestep>%.10g</Timestep>\n"
            "\t\t\t\t<RootPosition>%.6g %.6g %.6g</RootPosition>\n"
            "\t\t\t\t<RootRotation>%.6g %.6g %.6g</RootRotation>\n"
            "\t\t\t\t<JointPosition>" + "%.6g " * n_dof + "</JointPosition>\n"
            f"\t\t\t\t<JointVelocity>{zeros}</JointVelocity>\n"
            f"\t\t\t\t<JointAcceleration>{zeros}</JointAcceleration>\n"
            "\t\t\t</MotionFrame>\n")


def write_mmm(motion: Motion, path: str | Path, *, fsync: bool = True) -> None:
    """Write ``motion`` (on an MMM skeleton) as a KIT MMM XML file, atomically.

    Values are printed with 6 significant digits, like KIT's own files (timesteps with 10,
    so that long motions keep their frame rate); root position in mm. The subject height
    comes from the skeleton, the mass from ``meta["mass"]``.

    ``fsync=False`` skips forcing the file to disk (see :func:`utils.atomic.atomic_write`).

    Raises:
        SkeletonError: if the motion's skeleton is not the MMM model.
    """
    sk = motion.skeleton
    height = mmm_height(sk)
    col = {n: i for i, n in enumerate(sk.dof_names)}
    if sorted(col) != sorted(MMM_DOF_ORDER):
        raise SkeletonError(f"skeleton {sk.name!r} does not have the 44 MMM DOFs")
    cols = [col[n] for n in MMM_DOF_ORDER]
    T = motion.n_frames
    data = np.concatenate([
        (np.arange(T) / motion.fps)[:, None],
        motion.root_translation / sk.file_unit,
        motion.root_rotation[:, ::-1],  # (yaw, pitch, roll) -> file order roll pitch yaw
        motion.joint_angles[:, cols]], axis=1)
    mass = motion.meta.get("mass")
    mass = f"\t\t\t<Mass>{float(mass):.6g}</Mass>\n" if mass else ""
    name = escape(str(motion.meta.get("subject") or motion.name), {"'": "&apos;", '"': "&quot;"})
    joints = "".join(f"\t\t\t<Joint name='{n}'/>\n" for n in MMM_DOF_ORDER)
    # one printf over all frames: the corpus tools write thousands of files
    body = (_frame_template(len(MMM_DOF_ORDER)) * T) % tuple(data.ravel().tolist())
    with atomic_write(path, fsync=fsync) as fh:
        fh.write(_HEAD.format(name=name, height=height, mass=mass, joints=joints))
        fh.write(body)
        fh.write(_TAIL)

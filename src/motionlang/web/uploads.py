"""Uploaded motion files, read as the command line reads them.

An upload is a list of ``(file name, bytes)``: one motion file (``.bvh``, ``.xml`` MMM,
``.mat``), or an ``.amc`` with its ``.asf``, and optionally its joint map (``.json``). The bytes go to a private temporary folder
(never a user's folder) under their own base name, are read with :func:`motionlang.api.
read_mapped` (so every ``MOTIONLANG_MAX_*`` limit of ``utils.limits`` applies, as for the
CLI) and the folder is removed before the answer goes back. A reader's error comes back as
one line naming the uploaded file, without the temporary folder.
"""
from __future__ import annotations

import re
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path

from motionlang.analysis.rate import at_its_rate
from motionlang.api import read_mapped
from motionlang.errors import MotionlangError
from motionlang.formats import READ_EXTENSIONS
from motionlang.kinematics.motion import Motion

#: what an upload may hold besides motion files: the skeleton of an ``.amc``, and a joint
#: map (``motionlang rig template``) for a rig that no built-in map fits
SKELETON_EXTENSIONS = (".asf", ".json")
#: the readers' advice for the command line, and what a page's user does instead
_CLI_ADVICE = ("pass --joint-map FILE", "upload its joint map (.json) with the file")
_UNSAFE = re.compile(r"[^A-Za-z0-9._ -]+")
#: longest stem of an uploaded file's name kept (file systems take 255 bytes)
NAME_CHARS = 100

Upload = tuple[str, bytes]


def safe_name(name: str) -> str:
    """The base name of an uploaded file with anything but letters, digits, ``._ -``
    replaced, its stem cut to :data:`NAME_CHARS`; never empty, never a path."""
    base = _UNSAFE.sub("_", Path(name.replace("\\", "/")).name).strip(" .")
    stem, dot, ext = base.rpartition(".")
    if not dot or len(ext) > 16:   # no extension (or a name whose last dot is not one)
        stem, dot, ext = base, "", ""
    return (stem[:NAME_CHARS] + dot + ext).strip(" .") or "upload"


def check_upload(files: Sequence[Upload], max_bytes: int) -> None:
    """Refuse an upload that is empty, too big, or not one motion (an AMC with one ASF).

    Raises:
        MotionlangError: one line naming the file and the problem.
    """
    if not files:
        raise MotionlangError("no file was uploaded")
    total = sum(len(data) for _, data in files)
    if total > max_bytes:
        raise MotionlangError(f"the upload is {total / (1 << 20):.1f} MiB; the largest this "
                              f"server takes is {max_bytes / (1 << 20):.1f} MiB "
                              "(motionlang serve --max-upload-mb)")
    exts = [Path(name).suffix.lower() for name, _ in files]
    for (name, data), ext in zip(files, exts):
        if ext not in READ_EXTENSIONS + SKELETON_EXTENSIONS:
            raise MotionlangError(f"{safe_name(name)}: not a motion file (expected "
                                  f"{', '.join(READ_EXTENSIONS + SKELETON_EXTENSIONS)})")
        if not data:
            raise MotionlangError(f"{safe_name(name)}: the file is empty")
    motions = [n for (n, _), e in zip(files, exts) if e in READ_EXTENSIONS]
    if len(motions) != 1:
        raise MotionlangError(f"upload one motion file (an .amc with its .asf), got "
                              f"{len(motions)}: {', '.join(safe_name(n) for n in motions)}"
                              if motions else "the upload holds no motion file, only "
                              f"{', '.join(safe_name(n) for n, _ in files)}")
    skeletons = exts.count(".asf")
    if skeletons > 1 or (skeletons and ".amc" not in exts):
        raise MotionlangError("an .asf skeleton goes with one .amc motion")
    if exts.count(".json") > 1:
        raise MotionlangError("upload one joint map (.json) with the motion file")
    if ".amc" in exts and not skeletons:
        raise MotionlangError(f"{safe_name(motions[0])}: an .amc motion needs its .asf "
                              "skeleton: upload both files together")


def page_message(exc: BaseException | str, folder: Path | None = None) -> str:
    """An error's line as the page shows it: without the temporary ``folder``, and with
    the command line's advice about joint maps said as the page's."""
    text = str(exc).replace(f"{folder}/", "") if folder is not None else str(exc)
    return text.replace(*_CLI_ADVICE)


def read_upload(files: Sequence[Upload], max_bytes: int) -> Motion:
    """The motion of an upload (see the module docstring), named after its file.

    Raises:
        MotionlangError: a bad upload (:func:`check_upload`) or the reader's error.
    """
    check_upload(files, max_bytes)
    with tempfile.TemporaryDirectory(prefix="motionlang-serve-") as tmp:
        folder = Path(tmp)
        paths = []
        for name, data in files:
            path = folder / safe_name(name)
            path.write_bytes(data)
            paths.append(path)
        motion_path = next(p for p in paths if p.suffix.lower() in READ_EXTENSIONS)
        extra = {".asf": "skeleton", ".json": "joint_map"}
        kw = {extra[p.suffix.lower()]: p for p in paths if p.suffix.lower() in extra}
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                motion = read_mapped(motion_path, **kw)
        except MotionlangError as exc:   # the reader names the file by its temporary path
            raise MotionlangError(page_message(exc, folder)) from None
        except (ValueError, OSError) as exc:   # a reader's slip: still one line, no trace
            raise MotionlangError(f"{motion_path.name}: cannot read it ({exc})") from None
    for w in caught:   # the reader's notes, without the temporary folder, for the page
        warnings.warn(page_message(w.message, folder), w.category, stacklevel=2)
    motion.meta.pop("path", None)
    # a header's rate its body contradicts: read at the body's, as the command line does
    # (``meta["declared_fps"]`` keeps the header's), with a warning the page can show
    return at_its_rate(motion, motion_path.name, advice=None).replace(name=motion_path.stem)

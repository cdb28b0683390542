"""Uploaded motion files, read as the command line reads them.

An upload is a list of ``(file name, bytes)``: one motion file (``.bvh``, ``.xml`` MMM,
``.mat``), or an ``.amc`` with its ``.asf``. The bytes go to a private temporary folder
(never a user's folder) under their own base name, are read with :func:`motionlang.api.
read_mapped` (so every ``MOTIONLANG_MAX_*`` limit of ``utils.limits`` applies, as for the
CLI) and the folder is removed before the answer goes back. A reader's error comes back as
one line naming the uploaded file, without the temporary folder.
"""
from __future__ import annotations

import re
import tempfile
from collections.abc import Sequence
from pathlib import Path

from motionlang.errors import MotionlangError
from motionlang.formats import READ_EXTENSIONS
from motionlang.kinematics.motion import Motion

#: what an upload may hold besides motion files: the skeleton of an ``.amc``
SKELETON_EXTENSIONS = (".asf",)
_UNSAFE = re.compile(r"[^A-Za-z0-9._ -]+")

Upload = tuple[str, bytes]


def safe_name(name: str) -> str:
    """The base name of an uploaded file with anything but letters, digits, ``._ -``
    replaced; never empty, never a path."""
    base = _UNSAFE.sub("_", Path(name.replace("\\", "/")).name).strip(" .")
    return base or "upload"


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
    if ".amc" in exts and not skeletons:
        raise MotionlangError(f"{safe_name(motions[0])}: an .amc motion needs its .asf "
                              "skeleton: upload both files together")


def read_upload(files: Sequence[Upload], max_bytes: int) -> Motion:
    """The motion of an upload (see the module docstring), named after its file.

    Raises:
        MotionlangError: a bad upload (:func:`check_upload`) or the reader's error.
    """
    from motionlang.api import read_mapped
    check_upload(files, max_bytes)
    with tempfile.TemporaryDirectory(prefix="motionlang-serve-") as tmp:
        folder = Path(tmp)
        paths = []
        for name, data in files:
            path = folder / safe_name(name)
            path.write_bytes(data)
            paths.append(path)
        motion_path = next(p for p in paths if p.suffix.lower() in READ_EXTENSIONS)
        asf = next((p for p in paths if p.suffix.lower() == ".asf"), None)
        try:
            motion = read_mapped(motion_path, **({"skeleton": asf} if asf else {}))
        except MotionlangError as exc:   # the reader names the file by its temporary path
            raise MotionlangError(str(exc).replace(f"{folder}/", "")) from None
        except (ValueError, OSError) as exc:   # a reader's slip: still one line, no trace
            raise MotionlangError(f"{motion_path.name}: cannot read it ({exc})") from None
    motion.meta.pop("path", None)
    return motion.replace(name=motion_path.stem)

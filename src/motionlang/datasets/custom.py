"""A user's own motion-language dataset: a folder of motion files plus a captions file.

Layout::

    my_data/
        captions.csv        # header "file,text"; or captions.jsonl: {"file": ..., "text": ...}
        walk_01.bvh
        jump/02.amc         # ASF/AMC: the .asf is found next to the .amc
        jump/02.asf

``file`` is relative to the folder (``/`` or ``\\`` separated) and may not leave it; a
file may have several caption lines. Motion files without captions are kept with no
annotations, like KIT-ML records without any.
"""
from __future__ import annotations

import csv
import io
import posixpath
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from motionlang.errors import DatasetError, MotionlangError
from motionlang.formats import (
    read_joint_map,
    read_motion,  # lower layer, loaded lazily
)
from motionlang.utils import limits
from motionlang.utils.paths import leads_outside
from motionlang.utils.sidecar import check_name, check_text, parse_json, read_text

if TYPE_CHECKING:
    from motionlang.kinematics import Motion

MOTION_EXTENSIONS = (".bvh", ".amc", ".xml")
CAPTION_NAMES = ("captions.csv", "captions.jsonl")


@dataclass
class CustomRecord:
    """One motion file and its captions (fields as ``KitMLRecord`` where they overlap).

    Attributes:
        id: path relative to the dataset folder without extension, ``/``-separated.
        path: the motion file.
        annotations: its captions in file order (possibly none).
        meta: ``{"captions_lines": [...]}`` and anything the caller adds.
    """
    id: str
    path: Path
    annotations: list[str] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    fps: float | None = None
    joint_map: dict | None = None

    @property
    def has_annotations(self) -> bool:
        return bool(self.annotations)

    def load_motion(self) -> Motion:
        """Read the file with ``motionlang.formats.read_motion`` (ASF found automatically;
        the dataset's joint map, if any, attached)."""
        return read_motion(self.path, fps=self.fps, joint_map=self.joint_map)


def _read_csv(path: Path, text: str) -> list[tuple[int, str, str]]:
    rows = []
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    start = 1   # the line the next row starts on
    try:
        header = next(reader, None)
        if header is None or [h.strip().lower() for h in header[:2]] != ["file", "text"]:
            raise DatasetError(f"{path}:1: expected the header 'file,text', got {header}")
        start = reader.line_num + 1
        for row in reader:
            line, start = start, reader.line_num + 1
            if line != reader.line_num:
                # a quote left open takes the lines after it into one field
                raise DatasetError(f"{path}:{line}: a quoted field runs on to line "
                                   f"{reader.line_num} (an unterminated quote?)")
            if not any(c.strip() for c in row):
                continue
            if len(row) < 2:
                raise DatasetError(f"{path}:{line}: expected 2 columns (file,text), "
                                   f"got {len(row)}")
            rows.append((line, row[0].strip(), row[1].strip()))
    except csv.Error as exc:
        why = str(exc)
        if "unexpected end of data" in why:
            why = "a quote is never closed"
        elif "field limit" in why:
            why = (f"a field longer than {csv.field_size_limit():,} characters; a caption "
                   f"has at most {limits.current().max_caption_chars:,}")
        raise DatasetError(f"{path}:{start}: malformed CSV ({why})") from None
    return rows


def _read_jsonl(path: Path, text: str) -> list[tuple[int, str, str]]:
    rows = []
    for lineno, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        obj = parse_json(line, f"{path}:{lineno}")
        if not isinstance(obj, dict) or not isinstance(obj.get("file"), str) \
                or not isinstance(obj.get("text"), str):
            raise DatasetError(f"{path}:{lineno}: expected {{\"file\": str, \"text\": str}}")
        rows.append((lineno, obj["file"].strip(), obj["text"].strip()))
    return rows


def read_captions(path: str | Path) -> list[tuple[int, str, str]]:
    """``(line, file, text)`` rows of a captions file (``.csv`` or ``.jsonl``/``.json``;
    UTF-8, a byte-order mark allowed).

    The one reader of caption files: a regular file only (a FIFO or folder is refused by
    name), every caption one line of at most ``max_caption_chars`` characters without
    control characters, every file name without them
    (:mod:`motionlang.utils.sidecar`).

    Raises:
        DatasetError: ``PATH:LINE: ...`` for the first bad row (an unterminated quote names
            the line it opens on).
    """
    path = Path(path)
    if not path.exists():
        raise DatasetError(f"{path}: captions file not found")
    try:
        text = read_text(path, "captions file")
        rows = _read_csv(path, text) if path.suffix.lower() == ".csv" else \
            _read_jsonl(path, text)
        for line, f, caption in rows:
            where = f"{path}:{line}"
            if not f:
                raise DatasetError(f"{where}: empty 'file'")
            if not caption:
                raise DatasetError(f"{where}: empty 'text' for {f}")
            check_name(f, where, "file name")
            check_text(caption, where)
    except DatasetError:
        raise
    except MotionlangError as exc:
        raise DatasetError(str(exc)) from None
    return rows


JOINT_MAP_NAME = "joint_map.json"


def load_custom(folder: str | Path, captions: str | Path | None = None, *,
                fps: float | None = None, joint_map: str | Path | dict | None = None
                ) -> list[CustomRecord]:
    """Records of a folder of motion files and its captions, sorted by id.

    Args:
        folder: dataset folder (motion files searched recursively).
        captions: captions file (default: ``captions.csv`` or ``captions.jsonl`` in ``folder``).
        fps: passed to the reader (AMC frame rate; other formats are resampled).
        joint_map: how the folder's rig maps onto the 21-joint body (a map dict or JSON
            file; default: ``joint_map.json`` in ``folder`` if there is one, else the
            built-in maps chosen by joint names).

    Raises:
        DatasetError: missing folder or captions file, a bad row, or a row naming a motion
            file that does not exist, is not a motion file, or is outside the folder
            (captions file and line named).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DatasetError(f"{folder}: dataset folder not found")
    if captions is None:
        found = [folder / n for n in CAPTION_NAMES if (folder / n).is_file()]
        if len(found) != 1:
            raise DatasetError(f"{folder}: expected one of {', '.join(CAPTION_NAMES)} "
                               f"(found {len(found)}); pass captions=")
        captions = found[0]
    captions = Path(captions)
    if joint_map is None and (folder / JOINT_MAP_NAME).is_file():
        joint_map = folder / JOINT_MAP_NAME
    if joint_map is not None and not isinstance(joint_map, dict):
        joint_map = read_joint_map(joint_map)
    records: dict[str, CustomRecord] = {}  # by path in the folder, not by resolved path
    real = folder.resolve()
    for p in sorted(folder.rglob("*")):
        # a file link out of the folder is left out like a folder link (never descended
        # into), so a caption naming it is an error, not a read of a file elsewhere
        if p.suffix.lower() in MOTION_EXTENSIONS and p.is_file() and not leads_outside(p, real):
            rel = p.relative_to(folder)
            if p.suffix.lower() == ".xml" and not p.name.endswith("_mmm.xml"):
                continue  # only MMM motions; other XML (model files) is not a motion
            records[rel.as_posix()] = CustomRecord(rel.with_suffix("").as_posix(), p,
                                                   meta={"captions_lines": []}, fps=fps,
                                                   joint_map=joint_map)
    for line, f, text in read_captions(captions):
        rel = _inside(f, folder, f"{captions}:{line}")
        rec = records.get(rel)
        if rec is None:
            raise DatasetError(f"{captions}:{line}: unknown motion file {f!r} "
                               f"({_why_unknown(folder, rel)})")
        rec.annotations.append(text)
        rec.meta["captions_lines"].append(line)
    return sorted(records.values(), key=lambda r: r.id)


def _why_unknown(folder: Path, rel: str) -> str:
    """Why no motion file of ``folder`` has the path ``rel``."""
    target = folder / rel
    try:
        if not target.exists():
            return f"not found in {folder}"
        if rel != "." and folder.resolve() not in target.resolve().parents:
            return f"a symbolic link in {folder} leads outside it"
    except OSError as exc:
        return f"cannot be read: {exc.strerror or exc}"
    return f"not a motion file ({', '.join(MOTION_EXTENSIONS)}) in {folder}"


def _inside(name: str, folder: Path, where: str) -> str:
    """A caption's ``file`` as a normalised ``/``-separated path inside ``folder``.

    Matched against the files found in the folder by that path (never by resolving links,
    which would let ``../outside/x.bvh`` through wherever a link inside points there).

    Raises:
        DatasetError: an absolute path, or one that ``..`` takes out of the folder.
    """
    posix = name.replace("\\", "/")
    norm = posixpath.normpath(posix)
    if posix.startswith("/") or re.match(r"^[A-Za-z]:", posix) or "\0" in posix or \
            norm == ".." or norm.startswith("../"):
        raise DatasetError(f"{where}: motion file {name!r} is outside the dataset folder "
                           f"{folder} (paths are relative to it and stay inside)")
    return norm

"""A user's own motion library as training data, captioned without anyone writing a caption:
``--data library:DIR`` (and ``--data analysis:DIR``).

Each motion file under the folder (any rig the 21-joint body maps; recursively) becomes a
record whose captions are:

* the grounded analysis' sentence of it (``motionlang.analysis``: what the body does, from
  physics and geometry alone), where the analysis can tell;
* with ``library:``, also the folder's own captions where it has a ``captions.csv`` or
  ``captions.jsonl`` (``datasets.custom``), and the words of the file's path where they are
  words a motion is described with ("jump/fast_02.bvh" -> "a person jumps fast"); a name
  such as ``take_0412.bvh`` gives nothing. ``analysis:`` uses the analysis alone: for a
  library whose names are its labels, to score against them.

Split: by the hash of the file's stem, so that the copies of one take in several rigs
(``iclone/05_02.bvh``, ``secondlife/05_02.bvh``) fall in the same split and a held-out take
is held out in every rig; about 80 / 10 / 10.
"""
from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from motionlang.analysis import CANNOT_TELL, analyse
from motionlang.analysis.words import ACTION_WORDS
from motionlang.datasets.canonical import canonical_text
from motionlang.datasets.custom import CAPTION_NAMES, read_captions
from motionlang.errors import DatasetError, MotionlangError
from motionlang.formats import is_motion_file, read_motion

if TYPE_CHECKING:
    from motionlang.kinematics import Motion

_ACTION = {w for ws in ACTION_WORDS.values() for w in ws}
#: words of a file name that describe a motion besides its action words
NAME_WORDS = frozenset({
    "left", "right", "forward", "forwards", "backward", "backwards", "back", "fast", "slow",
    "slowly", "quickly", "quick", "up", "down", "around", "sideways", "side", "hand",
    "hands", "arm", "arms", "leg", "legs", "foot", "feet", "head", "circle", "stairs",
    "ball", "chair", "floor", "ground", "high", "low", "both", "over", "across", "away"})
_TOKEN = re.compile(r"[a-z]+")


@dataclass
class LibraryRecord:
    """One motion file of a library and the captions made for it.

    Attributes:
        id: the path under the folder without its extension, ``/``-separated.
        path: the motion file.
        annotations: its captions (the analysis' sentence first).
        split: ``"train"``, ``"val"`` or ``"test"`` (module docstring).
        meta: ``{"sources": [...]}``: where each caption came from.
    """

    id: str
    path: Path
    annotations: list[str] = field(default_factory=list)
    split: str = "train"
    meta: dict = field(default_factory=dict)

    @property
    def has_annotations(self) -> bool:
        return bool(self.annotations)

    def load_motion(self) -> Motion:
        return read_motion(self.path)


def split_of(stem: str) -> str:
    """The split of a take by the hash of its file's stem (about 80 / 10 / 10)."""
    h = int(hashlib.sha256(stem.encode("utf-8")).hexdigest()[:8], 16) % 10
    return "test" if h == 0 else "val" if h == 1 else "train"


def name_caption(rel: str) -> str | None:
    """A caption from the words of a path under the library, or None where they name no
    action ("jump/fast_02.bvh" -> "a person jumps fast")."""
    words = [w for w in _TOKEN.findall(Path(rel).with_suffix("").as_posix().lower())
             if w in _ACTION or w in NAME_WORDS]
    if not any(w in _ACTION for w in words):
        return None
    return canonical_text("a person " + " ".join(dict.fromkeys(words)))


def load_library(folder: str | Path, *, names: bool = True,
                 max_seconds: float | None = None) -> list[LibraryRecord]:
    """The records of a library folder, sorted by id (module docstring).

    Args:
        names: also the folder's captions file and the words of the paths (``library:``);
            False: the analysis' sentences alone (``analysis:``).
        max_seconds: leave out takes this long or longer.

    Raises:
        DatasetError: no such folder, or no motion file in it.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DatasetError(f"{folder}: library folder not found")
    given: dict[str, list[str]] = {}
    captions = [folder / n for n in CAPTION_NAMES if (folder / n).is_file()]
    if names and captions:
        for _, f, text in read_captions(captions[0]):
            given.setdefault(Path(f).as_posix(), []).append(text)
    out = []
    for p in sorted(folder.rglob("*")):
        if not p.is_file() or p.suffix.lower() == ".mat" or not is_motion_file(p):
            continue
        rel = p.relative_to(folder).as_posix()
        rec = LibraryRecord(str(Path(rel).with_suffix("").as_posix()), p,
                            split=split_of(p.stem), meta={"sources": []})
        try:
            motion = read_motion(p)
            if max_seconds is not None and motion.duration >= max_seconds:
                continue
            sentence = analyse(motion).sentence()
        except MotionlangError:
            continue   # a file that does not read (or no body the analysis reads) is left out
        if sentence != CANNOT_TELL:
            rec.annotations.append(sentence)
            rec.meta["sources"].append("analysis")
        if names:
            for text in given.get(rel, []):
                rec.annotations.append(text)
                rec.meta["sources"].append("captions")
            named = name_caption(rel)
            if named is not None:
                rec.annotations.append(named)
                rec.meta["sources"].append("name")
        out.append(rec)
    if not out:
        raise DatasetError(f"{folder}: no motion file the library reader takes")
    return out

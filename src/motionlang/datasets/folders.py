"""One dataset folder, either kind: a custom folder (motion files and a captions file,
:mod:`.custom`) or a KIT-ML-format release (:mod:`.kitml`); its records, its summary and a
seeded split of it (``motionlang data info | split``).

A folder holding a captions file is custom even if its motions are MMM files named as
KIT-ML's: the captions file is what the user wrote.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from motionlang.datasets.custom import CAPTION_NAMES, load_custom
from motionlang.datasets.kitml import kitml_summary, load_kitml
from motionlang.datasets.splits import random_split, save_splits
from motionlang.errors import DatasetError


def is_custom(folder: str | Path) -> bool:
    """Whether ``folder`` holds a captions file (``custom.CAPTION_NAMES``)."""
    return any((Path(folder) / n).is_file() for n in CAPTION_NAMES)


def folder_records(folder: str | Path, max_seconds: float | None = 30.0) -> list:
    """The records of a folder of either kind; ``max_seconds`` filters KIT-ML motions only
    (custom folders are read whole)."""
    if is_custom(folder):
        return load_custom(folder)
    return load_kitml(folder, max_seconds=max_seconds)


def folder_summary(folder: str | Path, max_seconds: float = 30.0) -> dict:
    """Counts of a folder: ``{"kind": "custom", "root", "motions", "annotations",
    "without_annotations"}``, or ``{"kind": "kitml", **kitml.kitml_summary(...)}`` (all
    motions and those shorter than ``max_seconds``, with durations).

    Raises:
        DatasetError: no such folder, or unreadable files (named).
    """
    if not is_custom(folder):
        return {"kind": "kitml", **kitml_summary(folder, max_seconds=max_seconds)}
    recs = folder_records(folder, None)
    return {"root": str(Path(folder)), "kind": "custom", "motions": len(recs),
            "annotations": sum(len(r.annotations) for r in recs),
            "without_annotations": sum(not r.has_annotations for r in recs)}


def summary_text(info: dict) -> str:
    """:func:`folder_summary` as ``motionlang data info`` prints it."""
    lines = [f"{info['kind']} dataset at {info['root']}"]
    if info["kind"] == "custom":
        return "\n".join([*lines, f"  motions {info['motions']}, annotations "
                           f"{info['annotations']}, without annotations "
                           f"{info['without_annotations']}"])
    for part, title in (("all", "all motions"), ("kept", f"< {info['max_seconds']:g} s")):
        s = info[part]
        d = s["duration_s"]
        dur = "" if d["min"] is None else (f", duration min/median/max "
                                           f"{d['min']:.2f}/{d['median']:.2f}/{d['max']:.2f} s")
        lines.append(f"  {title:>12}: motions {s['motions']}, annotations {s['annotations']}, "
                     f"without annotations {s['without_annotations']}, {s['hours']:.2f} h{dur}")
    return "\n".join(lines)


def split_folder(folder: str | Path, out: str | Path, fractions: Sequence[float] = (0.8, 0.1, 0.1),
                 seed: int = 0, max_seconds: float | None = 30.0) -> dict[Path, int]:
    """Split a folder's motions at random (``splits.random_split``) into ``out``'s
    ``train.txt``, ``val.txt`` (with 3 fractions), ``test.txt``; ``{file: ids}``.

    Raises:
        DatasetError: no motions, or fractions that are not 2 or 3 summing to 1.
    """
    recs = folder_records(folder, max_seconds)
    if not recs:
        raise DatasetError(f"{folder}: no motions to split")
    splits = random_split([r.id for r in recs], fractions, seed=seed)
    return {path: len(ids) for path, ids in zip(save_splits(splits, out), splits.values())}

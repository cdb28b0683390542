"""Train/validation/test splits: seeded random splits and the published split files.

A split file is one id per line (``00001``; mirrored copies as ``M00001``). Random splits
keep a motion and its mirrored copy in the same part, so a mirrored training motion never
leaks into the test set.
"""
from __future__ import annotations

import contextlib
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from motionlang.errors import DatasetError
from motionlang.utils.atomic import atomic_path, new_folder

SPLIT_NAMES = {2: ("train", "test"), 3: ("train", "val", "test")}


def _base_id(mid: str) -> str:
    return mid[1:] if mid[:1] == "M" and mid[1:].isdigit() else mid


def random_split(ids: Iterable[str], fractions: Sequence[float] = (0.8, 0.1, 0.1),
                 seed: int = 0) -> dict[str, list[str]]:
    """Split ``ids`` at random into ``train/val/test`` (3 fractions) or ``train/test`` (2).

    Ids are grouped by base id (``M00001`` with ``00001``) and the groups are shuffled with
    ``numpy.random.default_rng(seed)``, so the result depends only on the set of ids and the
    seed. Part sizes (in groups) are ``round(f * n)`` for all parts but the last.

    Returns:
        ``{"train": [...], "val": [...], "test": [...]}``, each sorted.
    """
    fractions = [float(f) for f in fractions]
    if len(fractions) not in SPLIT_NAMES or any(f < 0 for f in fractions) \
            or abs(sum(fractions) - 1.0) > 1e-6:
        raise DatasetError(f"split fractions must be 2 or 3 non-negative numbers summing to 1, "
                           f"got {fractions}")
    groups: dict[str, list[str]] = {}
    for mid in sorted(set(ids)):
        groups.setdefault(_base_id(mid), []).append(mid)
    keys = sorted(groups)
    order = np.random.default_rng(seed).permutation(len(keys))
    names = SPLIT_NAMES[len(fractions)]
    out: dict[str, list[str]] = {}
    start = 0
    for i, (name, f) in enumerate(zip(names, fractions)):
        stop = len(keys) if i == len(names) - 1 else min(len(keys), start + round(f * len(keys)))
        out[name] = sorted(m for j in order[start:stop] for m in groups[keys[j]])
        start = stop
    return out


def load_split(path: str | Path) -> list[str]:
    """Ids of one split file (blank lines ignored, order kept)."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{path}: cannot read split file ({exc})") from None
    ids = []
    for lineno, line in enumerate(lines, 1):
        s = line.strip()
        if not s:
            continue
        if len(s.split()) != 1:
            raise DatasetError(f"{path}:{lineno}: expected one id per line, got {line!r}")
        ids.append(s)
    return ids


def load_splits(folder: str | Path) -> dict[str, list[str]]:
    """Every ``*.txt`` split file of a folder, keyed by file stem."""
    folder = Path(folder)
    files = sorted(folder.glob("*.txt"))
    if not files:
        raise DatasetError(f"{folder}: no split files (*.txt)")
    return {p.stem: load_split(p) for p in files}


def save_splits(splits: dict[str, list[str]], folder: str | Path) -> list[Path]:
    """Write ``<name>.txt`` per split; return the paths.

    All or nothing: every file is written to a temporary file first and renamed only when
    all are complete, so a full disk never leaves ``train.txt`` without ``test.txt``; a
    folder made here is removed again on failure.
    """
    folder = Path(folder)
    paths = [folder / f"{name}.txt" for name in splits]
    with new_folder(folder), contextlib.ExitStack() as stack:
        for p, ids in zip(paths, splits.values()):   # every file complete before a rename
            tmp = stack.enter_context(atomic_path(p, min_bytes=0))
            tmp.write_text("".join(f"{i}\n" for i in ids), encoding="utf-8")
    return paths

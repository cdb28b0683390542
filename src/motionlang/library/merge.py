"""Join index shards into one index: ``motionlang merge-index A.idx B.idx ... -o library.idx``.

A folder too large for one machine is indexed as shards (``index DIR -o part_K.idx --shard
K/N`` on any machines: each takes the files whose path hashes to K of N, the same split on
every machine); the shards are then joined here. They must be of one model, windows and
detectors, and no take may be in two of them; the joined index is in the folder's order
(by path) and is brought up to date by ``index`` as any other (its files' digests are
kept, so unchanged files are not embedded again). Shards made on machines where the folder
lies elsewhere name its place there: ``root`` says where it is for the joined index.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.library.options import shard_of
from motionlang.library.store import IndexData, load_index, save_index


def merge_indexes(inputs: Sequence[str | Path], out: str | Path, *,
                  root: str | Path | None = None) -> IndexData:
    """The shards ``inputs`` joined into ``out`` (written atomically) and returned.

    Raises:
        MotionlangError: fewer than one input, a damaged one, shards of other models,
            windows, detectors or folders (without ``root``), or a take in two shards.
    """
    if not inputs:
        raise MotionlangError("merge-index needs at least one index to join")
    parts = [(Path(p), load_index(p)) for p in inputs]
    first_path, first = parts[0]
    for path, d in parts[1:]:
        for what, a, b in (("model", d.model, first.model),
                           ("windows", (d.window, d.hop), (first.window, first.hop)),
                           ("detectors (analysis version)", d.analysis, first.analysis)):
            if a != b:
                raise MotionlangError(f"{path}: made with other {what} than {first_path} "
                                      f"({a} against {b}); shards must be made alike")
        if root is None and d.root != first.root:
            raise MotionlangError(f"{path}: a shard of {d.root}, {first_path} of "
                                  f"{first.root}; pass root= (--root) to say where the folder is")
    blocks = []
    seen: dict[tuple[str, int], Path] = {}
    for path, d in parts:
        first_rows = d.first_rows
        for i, e in enumerate(d.entries):
            key = (e.path, e.sequence)
            if key in seen:
                raise MotionlangError(f"{path}: take {e.name!r} is in {seen[key]} too")
            seen[key] = path
            rows = slice(first_rows[i], first_rows[i + 1])
            blocks.append((e, d.vectors[rows], d.spans[rows]))
    blocks.sort(key=lambda b: (b[0].path, b[0].sequence))
    failed = sorted((f for _, d in parts for f in d.failed), key=lambda f: f.path)
    dim = next((v.shape[1] for _, v, _ in blocks if v.size), first.vectors.shape[1])
    merged = IndexData(first.model, str(root if root is not None else first.root),
                       first.window, first.hop, [e for e, _, _ in blocks], failed,
                       np.concatenate([v for _, v, _ in blocks]).astype(np.float32)
                       if blocks else np.zeros((0, dim), np.float32),
                       np.concatenate([s for _, _, s in blocks]) if blocks
                       else np.zeros((0, 2)), first.analysis, _shards(parts))
    save_index(merged, out)
    return merged


def _shards(parts: list[tuple[Path, IndexData]]) -> str:
    """The joined index's shard: "" when the parts are every shard K/N of one N (or whole
    folders), else the parts' shards listed."""
    given = [d.shard for _, d in parts]
    if all(not g for g in given):
        return ""
    split = {shard_of(g) for g in given if g}
    ns = {n for _, n in split}
    if len(ns) == 1 and not any(not g for g in given) and \
            {k for k, _ in split} == set(range(1, next(iter(ns)) + 1)):
        return ""
    return ",".join(sorted(set(given)))

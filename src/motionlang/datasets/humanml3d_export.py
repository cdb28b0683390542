"""Write any motionlang dataset in the HumanML3D layout (``motionlang data export-h3d``).

Records are anything with ``id``, ``annotations`` and ``load_motion()`` (KIT-ML, the
procedural corpus, a custom folder, a HumanML3D folder: ``datasets.seq2seq_pairs.
load_records``). The layout and what the rows mean: ``datasets.humanml3d`` and
``features.h3d_vectors``. Bodies:

* ``kit``: the 21-joint body of the real-rigs work (``features.joint_map.positions21``, the
  rig's built-in map or the joint map it was read with), 12.5 fps, millimetres. Any rig.
* ``smpl``: the 22 SMPL joints, 20 fps, metres, taken from a rig that has them by name
  (SMPL / SMPL-X names, or their BVH names ``Pelvis``, ``L_Hip``...). Other rigs are
  refused: the 21-joint body has no spine3, no collars and one neck point where SMPL has
  two, so an SMPL body made from it would be largely invented.

The whole folder is written under a temporary name next to ``out`` and renamed at the end:
an error leaves nothing behind. Splits: a seeded random split by motion (``random_split``),
mirrored copies in the split of their original. ``Mean.npy`` / ``Std.npy`` are computed over
every written row, mirrored ones included, as the public ``cal_mean_variance`` does.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from motionlang.datasets.humanml3d import JOINTS, TEXTS, VECS, format_caption_line
from motionlang.datasets.pos_tags import tag
from motionlang.datasets.splits import random_split
from motionlang.datasets.synth.augment import mirror_text
from motionlang.errors import DatasetError, MotionFormatError, SkeletonError
from motionlang.features.base import downsample
from motionlang.features.h3d_vectors import (
    H3D_BODIES,
    HEADINGS,
    H3DBody,
    group_std,
    joints_to_vectors,
    mirror_joints,
    vectors_to_joints,
)
from motionlang.features.joint_map import positions21
from motionlang.features.rig_maps import SMPL_JOINT_NAMES
from motionlang.utils.atomic import WriteError, make_temp

INFO_NAME = "h3d_export.json"


def _smpl_keys(name: str) -> tuple[str, ...]:
    """Accepted lower-case spellings of one SMPL joint: ``left_hip`` and ``l_hip``."""
    side = {"left": "l", "right": "r"}.get(name.split("_")[0])
    return (name,) if side is None else (name, side + name[name.index("_"):])


def smpl_joints(motion) -> np.ndarray:
    """(T, 22, 3) metres of the SMPL joints of a rig that has all of them by name (matched
    case-insensitively, ``namespace:`` dropped), in ``SMPL_JOINT_NAMES`` order.

    Raises:
        SkeletonError: the rig lacks some of them (the message says to use the kit body).
    """
    index = {}
    for i, n in enumerate(motion.skeleton.names):
        index.setdefault(n.rsplit(":", 1)[-1].lower(), i)
    found = [next((index[k] for k in _smpl_keys(n) if k in index), None)
             for n in SMPL_JOINT_NAMES]
    missing = [n for n, j in zip(SMPL_JOINT_NAMES, found) if j is None]
    if missing:
        raise SkeletonError(
            f"{motion.name}: --body smpl needs the 22 SMPL joints by name; rig "
            f"{motion.skeleton.name!r} lacks {', '.join(missing[:6])}"
            f"{' ...' if len(missing) > 6 else ''}; use --body kit (the 21-joint body, any rig)")
    return motion.positions()[:, found]


def body_joints(motion, body: H3DBody) -> np.ndarray:
    """A motion -> (T, J, 3) metres at ``body.fps``: the 21 KIT joints or the 22 SMPL ones."""
    m = downsample(motion, body.fps)
    return positions21(m) if body.name == "kit" else smpl_joints(m)


class _Moments:
    """Column mean and population variance over row blocks (Chan et al.'s merge)."""

    def __init__(self):
        self.n, self.mean, self.m2 = 0, None, None

    def add(self, x: np.ndarray) -> None:
        x = np.asarray(x, dtype=float)
        nb, mb = len(x), x.mean(axis=0)
        m2b = ((x - mb) ** 2).sum(axis=0)
        if self.n == 0:
            self.n, self.mean, self.m2 = nb, mb, m2b
            return
        n, d = self.n + nb, mb - self.mean
        self.mean = self.mean + d * nb / n
        self.m2 = self.m2 + m2b + d ** 2 * self.n * nb / n
        self.n = n

    def std(self) -> np.ndarray:
        return np.sqrt(self.m2 / self.n)


def _file_id(rid: str) -> str:
    """A record id as a file stem: path separators and the caption separator replaced."""
    return re.sub(r"[/\\#@\s]+", "_", str(rid)).strip("_") or "motion"


def _file_ids(records: Sequence, mirror: bool) -> list[str]:
    """The file stem of each record, checked for clashes (mirrored copies included)."""
    names: set[str] = set()
    out = []
    for rec in records:
        fid = _file_id(rec.id)
        mine = {fid, f"M{fid}"} if mirror else {fid}
        if mine & names:
            raise DatasetError(f"record {rec.id!r}: file name {fid!r} clashes with another "
                               "record (or its mirrored copy)")
        names |= mine
        out.append(fid)
    return out


def _prepare(job: tuple) -> list[tuple[str, np.ndarray, np.ndarray, list[str]]]:
    """One record -> ``[(file id, rows, joints, caption lines)]`` (float32, file units), its
    mirrored copy second; ``[]`` if it has fewer than 2 frames at the body's rate."""
    rec, fid, body, heading, mirror, tagger = job
    spec = H3D_BODIES[body]
    joints = body_joints(rec.load_motion(), spec)
    if len(joints) < 2:
        return []
    texts = list(rec.annotations)
    copies = [(fid, joints, texts)]
    if mirror:
        copies.append((f"M{fid}", mirror_joints(joints, spec), [mirror_text(t) for t in texts]))
    out = []
    for name, p, captions in copies:
        rows = joints_to_vectors(p / spec.unit, spec, heading)[0].astype(np.float32)
        out.append((name, rows, vectors_to_joints(rows, spec).astype(np.float32),
                    [format_caption_line(c, tagger(c)) for c in captions]))
    return out


def _prepare_in_worker(job: tuple) -> list:
    try:
        return _prepare(job)
    except MotionFormatError as exc:   # its constructor does not survive pickling
        raise DatasetError(str(exc)) from None


def _prepared(jobs: list, workers: int) -> Iterator[list]:
    """:func:`_prepare` of every job, in order, in ``workers`` processes; pending jobs are
    cancelled when the consumer stops (an error)."""
    if workers <= 1 or len(jobs) < 2:
        yield from map(_prepare, jobs)
        return
    pool = ProcessPoolExecutor(max_workers=workers)
    try:
        yield from pool.map(_prepare_in_worker, jobs,
                            chunksize=max(1, min(16, len(jobs) // (8 * workers))))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _write_splits(folder: Path, ids: list[str], mirrored: bool,
                  fractions: Sequence[float], seed: int) -> None:
    parts = random_split(ids, fractions, seed=seed)
    for name, part in parts.items():
        part = sorted(part + [f"M{i}" for i in part] if mirrored else part)
        (folder / f"{name}.txt").write_text("".join(f"{i}\n" for i in part), encoding="utf-8")
    every = sorted(ids + [f"M{i}" for i in ids] if mirrored else ids)
    (folder / "all.txt").write_text("".join(f"{i}\n" for i in every), encoding="utf-8")


@contextlib.contextmanager
def _staging(out: Path):
    """A temporary folder next to ``out``, renamed onto it if the block succeeds and removed
    if it fails. ``out`` must not exist or be an empty folder."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError(f"{out}: already exists and is not an empty folder; choose a new "
                           "output folder")
    try:   # named as utils.atomic names them, so a killed export's folder is swept later
        tmp = make_temp(out, ".partial", directory=True)
    except OSError as exc:
        raise WriteError(out, exc) from None
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)
        for sub in (VECS, JOINTS, TEXTS):
            (tmp / sub).mkdir()
        yield tmp
        if out.exists():
            out.rmdir()
        os.rename(tmp, out)
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(exc, OSError):
            raise WriteError(out, exc) from None
        raise


def export_h3d(records: Iterable, out: str | Path, body: str = "kit", *, mirror: bool = False,
               heading: str = "public", fractions: Sequence[float] = (0.8, 0.1, 0.1),
               seed: int = 0, tagger: Callable[[str], list[str]] | None = None,
               workers: int = 1,
               on_progress: Callable[[int, int, str], None] | None = None) -> dict:
    """Write ``records`` to ``out`` in the HumanML3D layout.

    Args:
        body: ``"kit"`` (any rig) or ``"smpl"`` (rigs with the SMPL joints).
        mirror: also write ``M<ID>``, the mirror image with left/right swapped in captions.
        heading: ``"public"`` or ``"body"`` (``features.h3d_vectors.heading_yaw``).
        fractions, seed: the random split by motion (``datasets.splits.random_split``).
        tagger: caption -> ``["word/POS", ...]`` (default ``datasets.pos_tags.tag``: lemmas and
            universal tags, offline; with
            ``workers > 1`` it must be picklable, a module-level function).
        workers: processes reading and converting motions (the files are the same for any
            number).
        on_progress: called as ``(done, total, id)`` after each record.

    Returns:
        the summary also written to ``h3d_export.json``: body, fps, unit, heading, counts,
        the ids skipped (fewer than 2 frames at the body's rate).

    Raises:
        DatasetError: ``out`` exists and is not empty, two records map to one file name.
        SkeletonError: a rig that cannot give the body's joints.
    """
    if body not in H3D_BODIES:
        raise DatasetError(f"unknown body {body!r} (kit or smpl)")
    if heading not in HEADINGS:
        raise DatasetError(f"unknown heading {heading!r} ({' or '.join(HEADINGS)})")
    spec, records = H3D_BODIES[body], list(records)
    fids = _file_ids(records, mirror)
    jobs = [(r, f, body, heading, mirror, tagger or tag) for r, f in zip(records, fids)]
    ids, skipped, moments = [], [], _Moments()
    with _staging(Path(out)) as tmp, contextlib.closing(_prepared(jobs, workers)) as results:
        for k, (rec, fid, written) in enumerate(zip(records, fids, results), 1):
            for name, rows, joints, lines in written:
                np.save(tmp / VECS / f"{name}.npy", rows)
                np.save(tmp / JOINTS / f"{name}.npy", joints)
                (tmp / TEXTS / f"{name}.txt").write_text("".join(f"{x}\n" for x in lines),
                                                         encoding="utf-8")
                moments.add(rows)
            if written:
                ids.append(fid)
            else:
                skipped.append(str(rec.id))
            if on_progress is not None:
                on_progress(k, len(records), str(rec.id))
        if not ids:
            raise DatasetError(f"nothing to export: no record has 2 frames at {spec.fps:g} fps")
        np.save(tmp / "Mean.npy", moments.mean.astype(np.float32))
        np.save(tmp / "Std.npy", group_std(moments.std(), spec.n_joints).astype(np.float32))
        _write_splits(tmp, ids, mirror, fractions, seed)
        info = {"format": "HumanML3D layout", "body": spec.name, "joints": spec.n_joints,
                "vector_dim": spec.dim, "fps": spec.fps, "unit_m": spec.unit,
                "heading": heading, "motions": len(ids), "mirrored": mirror,
                "rows": int(moments.n), "skipped": skipped}
        (tmp / INFO_NAME).write_text(json.dumps(info, indent=1), encoding="utf-8")
    return info

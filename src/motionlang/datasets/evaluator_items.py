"""The text-motion evaluator's (``models.evaluator``) training items, from any motionlang
dataset (its trainer is ``recipes.evaluator_train``).

Items: ``{"motion": (T-1, D) float32 HumanML3D vectors in the body's file unit, "caption",
"tokens": [word/POS] or None, "id"}``, one per caption of each motion. The rows are those
``motionlang data export-h3d`` writes (``features.h3d_vectors``): a HumanML3D-layout folder
of the same body gives its stored rows and tagged captions; any other dataset (KIT-ML, the
procedural corpus, a custom folder) has each motion taken to the body's joints
(``datasets.humanml3d_export.body_joints``: ``kit`` = the 21-joint body in millimetres,
any rig; ``smpl`` = 22 SMPL joints; each at its rate, ``features.h3d_vectors.H3D_BODIES``)
and turned into rows, and its captions tagged by ``models.evaluator.text.tag``. The model's ``collate`` normalises the
rows with the evaluator's mean/std, which :func:`fit_normalizer` sets from the training
motions as the public ``Mean.npy``/``Std.npy`` are made (each part of the row shares one
std).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from motionlang.datasets.humanml3d_export import body_joints
from motionlang.datasets.seq2seq_pairs import load_records
from motionlang.datasets.splits import random_split
from motionlang.errors import DatasetError
from motionlang.features.body21 import median_bones21, uniform_bones21
from motionlang.features.h3d_vectors import H3D_BODIES, group_std, joints_to_vectors

if TYPE_CHECKING:
    from motionlang.datasets.sources import Record


def body_joints_of(motion, body: str = "kit") -> np.ndarray:
    """A ``Motion`` -> (T, J, 3) metres of ``body`` at its rate (at least 2 frames)."""
    joints = body_joints(motion, H3D_BODIES[body])
    if len(joints) < 2:
        raise DatasetError(f"{motion.name}: too short for motion rows ({len(joints)} frame)")
    return joints


def joints_rows(joints: np.ndarray, body: str = "kit", bones=None) -> np.ndarray:
    """(T, J, 3) metres of ``body`` -> (T-1, D) float32 HumanML3D rows in its file unit;
    ``bones`` (20 lengths, m; ``kit`` only): laid on them first (``uniform_bones21``)."""
    spec = H3D_BODIES[body]
    if bones is not None:
        if body != "kit":
            raise DatasetError(f"uniform bones are for the kit body (21 joints), not {body}")
        joints = uniform_bones21(joints, bones)
    return joints_to_vectors(joints / spec.unit, spec)[0].astype(np.float32)


def motion_rows(motion, body: str = "kit", bones=None) -> np.ndarray:
    """A ``Motion`` -> (T-1, D) float32 HumanML3D rows of ``body`` (``"kit"``: D = 251,
    millimetres; ``"smpl"``: D = 263, metres); T is the frame count at the body's rate;
    ``bones``: see :func:`joints_rows`."""
    return joints_rows(body_joints_of(motion, body), body, bones)


def _record_joints(record, body: str) -> np.ndarray:
    """A record's (T, J, 3) metres of ``body``: a HumanML3D-layout record's own joints (exact
    and cheaper) when it is of that body, else its motion's (:func:`body_joints_of`)."""
    if getattr(getattr(record, "body", None), "name", None) == body and \
            hasattr(record, "load_joints"):
        return np.asarray(record.load_joints(), dtype=float)
    return body_joints_of(record.load_motion(), body)


def record_items(record, body: str = "kit", bones=None, joints: np.ndarray | None = None
                 ) -> list[dict]:
    """One item per caption of a record (``id``, ``annotations``, ``load_motion()``; a
    HumanML3D-layout record of ``body`` also ``load_vectors()`` and tagged captions, whose
    stored rows are used unless ``bones`` are given). ``joints``: the record's
    :func:`body_joints_of`, if already made."""
    spec = getattr(record, "body", None)
    stored = hasattr(record, "load_vectors") and getattr(spec, "name", None) == body
    tokens = list((getattr(record, "meta", None) or {}).get("tokens") or []) if stored else []
    if stored and bones is None:
        rows = np.asarray(record.load_vectors(), dtype=np.float32)
    else:
        if joints is None:
            joints = _record_joints(record, body)
        rows = joints_rows(joints, body, bones)
    tokens += [None] * (len(record.annotations) - len(tokens))
    return [{"motion": rows, "caption": c, "tokens": t or None, "id": str(record.id)}
            for c, t in zip(record.annotations, tokens)]


def fit_normalizer(items: Sequence[dict], body: str | None = "kit"
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std (D,) of the rows of the items' motions (each id counted once); with a
    ``body`` the std of each part of the HumanML3D row is its mean (``group_std``)."""
    seen, rows = set(), []
    for it in items:
        if it["id"] not in seen:
            seen.add(it["id"])
            rows.append(np.asarray(it["motion"], dtype=np.float64))
    if not rows:
        raise DatasetError("no motions to fit the evaluator's mean/std on")
    x = np.concatenate(rows)
    mean, std = x.mean(axis=0), x.std(axis=0)
    if body is not None:
        std = group_std(std, H3D_BODIES[body].n_joints)
    return mean, np.where(std > 0, std, 1.0)


@dataclass
class EvaluatorData:
    """Items per split (``{"train"|"val"|"test": [item]}``), the body of their rows and the
    records they came from (``{id: record}``: the motions and every caption, e.g. for the
    motion-to-text half of the yardstick)."""

    items: dict[str, list[dict]]
    body: str
    records: dict[str, Any] = field(default_factory=dict)
    bones: list[float] | None = None   # the body every motion was laid on, if one

    @property
    def motion_dim(self) -> int:
        return H3D_BODIES[self.body].dim


def build_evaluator_data(data: str | Path | Sequence[Record], body: str = "kit", *,
                         fractions: Sequence[float] = (0.8, 0.1, 0.1), seed: int = 0,
                         max_seconds: float | None = 30.0, bones=None) -> EvaluatorData:
    """Read ``data`` (anything ``datasets.seq2seq_pairs.load_records`` reads, or a list of
    records), split by motion — the folder's own split files when every record has a
    split, else a seeded ``random_split`` — and make the items of every split.

    ``bones``: None (each motion on its own bones), 20 lengths (m) to lay every motion on
    (``kit`` body), or ``"median"``: the training motions' median bone lengths (set in the
    result's ``bones``)."""
    if isinstance(data, (str, Path)):
        records = load_records(data, max_seconds)
    else:
        records = list(data)
    records = [r for r in records if r.annotations]
    if len(records) < 2:
        raise DatasetError(f"{data}: need at least 2 described motions, found {len(records)}")
    by_id = {str(r.id): r for r in records}
    if all(getattr(r, "split", None) for r in records):
        splits = {s: [i for i, r in by_id.items() if getattr(r, "split", None) == s]
                  for s in ("train", "val", "test")}
    else:
        splits = random_split(list(by_id), fractions, seed=seed)
    joints: dict[str, np.ndarray] = {}
    if isinstance(bones, str):
        if bones != "median" or body != "kit":
            raise DatasetError(f"bones={bones!r}: 'median' (kit body), a list of 20 lengths "
                               "or None")
        joints = {i: _record_joints(by_id[i], body) for i in splits.get("train") or list(by_id)}
        bones = median_bones21(joints.values())
    items = {s: [it for i in ids for it in record_items(by_id[i], body, bones, joints.get(i))]
             for s, ids in splits.items()}
    return EvaluatorData(items, body, by_id, None if bones is None else list(bones))

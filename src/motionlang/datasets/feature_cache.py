"""Features of a whole dataset, computed once and cached on disk.

``dataset_features(records, "positions", {"fps": 12.5})`` fits a feature set on the
records' motions, encodes every record and stores both in the ``.npz`` cache of
:mod:`motionlang.datasets.cache`. The cache key holds the identity (resolved path, size,
mtime) of every source file a record is read from, the record ids, the feature kind, its
options and ``CACHE_VERSION``: a second call with the same inputs is a hit (no motion is
read); changing an option or the records, or touching a source file, recomputes.

Records are anything with ``id`` and ``load_motion()`` whose file is ``mmm_path`` (KIT-ML)
or ``path`` (custom datasets; an ``.amc`` also depends on its ``.asf``).
"""
from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.datasets.cache import cached, file_identity
from motionlang.errors import MotionlangError
from motionlang.features.base import FeatureSet, features_from_dict, make_features
from motionlang.formats import find_asf
from motionlang.kinematics.from_positions import mirror_motion
from motionlang.utils.progress import progress

#: bump when any feature encoding, or what a reader makes of a file, changes, so that older
#: cache entries are not reused (2: the BVH reader leaves out an exporter's T-pose)
CACHE_VERSION = 2


@dataclass
class DatasetFeatures:
    """A fitted feature set and the encoded records.

    Attributes:
        features: the fitted :class:`FeatureSet` (its normaliser included).
        sequences: ``{record id: [(T_k, D) arrays]}`` — one array per record, or for
            ``angles`` one per downsampling offset (10 at 100 -> 10 Hz, Plappert 2018).
    """
    features: FeatureSet
    sequences: dict[str, list[np.ndarray]]


def record_sources(record: Any) -> list[Path]:
    """The files ``record.load_motion()`` reads: its motion file (and the ASF of an AMC)."""
    path = getattr(record, "mmm_path", None) or getattr(record, "path", None)
    if path is None:
        raise MotionlangError(f"record {getattr(record, 'id', record)!r} names no motion "
                              f"file (mmm_path or path)")
    path = Path(path)
    if path.suffix.lower() == ".amc":
        return [path, find_asf(path)]
    return [path]


def _identity(records: Sequence) -> list:
    return [[str(r.id), getattr(r, "fps", None), [file_identity(p) for p in record_sources(r)]]
            for r in records]


def _encode_record(fs: FeatureSet, motion) -> list[np.ndarray]:
    encode_all = getattr(fs, "encode_all", None)
    return list(encode_all(motion)) if encode_all is not None else [fs.encode(motion)]


def dataset_features(records: Sequence, kind: str, options: dict[str, Any] | None = None, *,
                     fit_records: Sequence | None = None, directory: str | Path | None = None,
                     refresh: bool = False, mirror: bool = False) -> DatasetFeatures:
    """Fit ``kind`` features (config ``options``) and encode ``records``, through the cache.

    Args:
        records: the records to encode (ids must be unique).
        kind: ``"angles"``, ``"positions"`` or ``"taylor"``.
        options: config fields of the feature set, e.g. ``{"fps": 12.5}``.
        fit_records: records to fit the normaliser on (default ``records``; pass the
            training split so validation and test data stay unseen).
        directory: cache folder (default ``$MOTIONLANG_CACHE`` or ``~/.cache/motionlang``).
        refresh: recompute even if cached.
        mirror: encode each record's motion mirrored left/right (``mirror_motion``), for
            augmentation; the features are still fitted on the unmirrored ``fit_records``
            (the same cache entry as without it).

    Returns:
        :class:`DatasetFeatures`; the arrays are identical whether loaded or computed.
    """
    records = list(records)
    fit_records = records if fit_records is None else list(fit_records)
    ids = [str(r.id) for r in records]
    if len(set(ids)) != len(ids):
        raise MotionlangError("dataset_features: record ids are not unique")
    if not fit_records:
        raise MotionlangError("dataset_features: no records to fit the features on")
    options = dict(options or {})
    make_features(kind, options)  # fail on a bad kind or option before touching the cache

    # rows of every record read while fitting, for encoding without reading them again
    # (feature sets whose encoding is normalise(rows); never for the mirrored pass)
    read: dict[str, np.ndarray] = {}

    def fit():
        fs = make_features(kind, options)
        by_id = {str(r.id): r for r in fit_records}
        if mirror or not fs.encodes_rows or not by_id.keys() <= set(ids):
            fs.fit(r.load_motion() for r in progress(fit_records, desc=f"fit {kind}",
                                                     unit="motion"))
        else:   # each motion read once: all records now, the fit on the training ones
            for r in progress(records, desc=f"read {kind}", unit="motion"):
                read[str(r.id)] = fs.rows(r.load_motion())
            fs.fit_rows([read[str(r.id)] for r in fit_records])
        return {"json": np.frombuffer(json.dumps(fs.to_dict()).encode("utf-8"), np.uint8)}

    key = {"v": CACHE_VERSION, "stage": "fit", "kind": kind, "options": options,
           "records": _identity(fit_records)}
    blob = cached(key, fit, name=f"fit-{kind}", directory=directory, refresh=refresh)
    fs = features_from_dict(json.loads(blob["json"].tobytes().decode("utf-8")))

    def encode():
        out = {}
        if read:
            for i, rid in enumerate(ids):
                out[f"{i}_0"] = fs.encode_rows(read.pop(rid))
            return out
        for i, r in enumerate(progress(records, desc=f"encode {kind}", unit="motion")):
            motion = r.load_motion()
            motion = mirror_motion(motion) if mirror else motion
            for k, seq in enumerate(_encode_record(fs, motion)):
                out[f"{i}_{k}"] = seq
        return out

    key = {"v": CACHE_VERSION, "stage": "encode", "features": fs.to_dict(),
           "records": _identity(records)}
    if mirror:   # keys without it stay those of earlier caches; "mirror_motion": not the
        key["mirror"] = "mirror_motion"   # Motion.mirror of before, wrong on some rigs
    arrays = cached(key, encode, name=f"encode-{kind}{'-mirrored' * mirror}",
                    directory=directory, refresh=refresh)
    sequences: dict[str, list[np.ndarray]] = {i: [] for i in ids}
    for name in sorted(arrays, key=lambda n: tuple(int(x) for x in n.split("_"))):
        i, _ = name.split("_")
        sequences[ids[int(i)]].append(arrays[name])
    return DatasetFeatures(fs, sequences)

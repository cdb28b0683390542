"""Approximate nearest windows for very large indexes: an HNSW graph of ``usearch`` (an
optional package, the ``ann`` extra) behind the same ``search`` call.

The graph is built once from the index's unit vectors and kept beside the index file
(``library.idx.usearch``, with ``.json`` naming the vectors it was built from: rows, size
and their SHA-256), so that a later query loads it instead of building it again; a graph
of other vectors is built anew. Writes are atomic. Exact search stays the default below
``search.ANN_MIN_ROWS`` windows, where it is fast enough and always right.
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.utils.atomic import atomic_write
from motionlang.utils.sidecar import load_json


def available() -> bool:
    """Whether ``usearch`` is installed."""
    return importlib.util.find_spec("usearch") is not None


def _digest(unit: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(unit, dtype=np.float32).tobytes()).hexdigest()


class Approximate:
    """An HNSW graph over ``unit`` (N, D) float32 rows (inner product = cosine).

    Args:
        unit: the index's unit vectors.
        cache: the graph's file beside the index (None: kept in memory only).
    """

    def __init__(self, unit: np.ndarray, cache: str | Path | None = None):
        try:
            from usearch.index import Index
        except ImportError:
            raise MotionlangError("backend 'usearch' needs the usearch package (pip install "
                                  "'motionlang[ann]' or usearch)") from None
        self.n, dim = unit.shape
        key = {"rows": int(self.n), "dim": int(dim), "sha256": _digest(unit)}
        self.graph = Index(ndim=dim, metric="ip", dtype="f32")
        cache = None if cache is None else Path(cache)
        meta = None if cache is None else cache.with_name(cache.name + ".json")
        if cache is not None and meta is not None and cache.is_file() and meta.is_file():
            try:
                if load_json(meta, "approximate index key") == key:
                    self.graph.load(str(cache))
                    return
            except (MotionlangError, RuntimeError, ValueError):
                pass   # a damaged or foreign graph: built again below
        # one thread: the graph (and so every approximate answer) is the same on every run;
        # threads adding at once link the rows in whatever order they come
        self.graph.add(np.arange(self.n), np.ascontiguousarray(unit, dtype=np.float32),
                       threads=1)
        if cache is not None and meta is not None:
            self._save(cache, meta, key)

    def _save(self, cache: Path, meta: Path, key: dict) -> None:
        tmp = cache.with_name(f".{cache.name}.{os.getpid()}.tmp")
        try:
            self.graph.save(str(tmp))
            os.replace(tmp, cache)
            with atomic_write(meta) as fh:
                fh.write(json.dumps(key) + "\n")
        except OSError:
            pass   # a read-only folder: the graph serves this process only
        finally:
            tmp.unlink(missing_ok=True)

    def best(self, q: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cosines) of about the ``m`` best rows for the unit query ``q``, best
        first."""
        found = self.graph.search(np.ascontiguousarray(q, dtype=np.float32), min(m, self.n))
        rows = np.asarray(found.keys, dtype=np.int64)
        return rows, 1.0 - np.asarray(found.distances, dtype=np.float32)

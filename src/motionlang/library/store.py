"""The index file: one ``.npz`` holding the window vectors, their spans and one JSON string.

Arrays (no pickled objects: read with ``allow_pickle=False``):

* ``vectors`` (N, D) float32: one vector per window, as the model gave it;
* ``spans`` (N, 2) float64: each window's (start, end) in seconds of its take;
* ``meta``: a JSON string: ``what``, ``format``, the model's identity (``name``, ``digest``),
  the indexed folder (``root``), the windows' ``window`` and ``hop`` (seconds), ``entries``
  (one per take, in row order: path relative to the root, ``sequence`` / ``sequences`` of a
  file holding several, size, mtime, ``sha256``, ``rig`` (joint count and map name),
  ``fps``, ``declared_fps`` (the header's rate where the body's was read instead; null
  else, or absent), ``duration`` (seconds), ``rows``, its number of windows, and ``findings``,
  what the analysis saw in it, ``library.grounded.FIELDS`` each; null in an index of
  format 1, which is read as it is and analysed on its next update) and ``failed`` (files
  skipped: path, size, mtime, sha256, one-line ``reason``), and ``analysis``, the version
  of the detectors that made the findings (``analysis.VERSION``; 0 where unknown), and
  ``shard`` ("K/N" for a shard of the folder, ``index --shard``; "" for all of it).

Reading checks every size and shape against the others before anything is used, so that a
damaged or foreign file is one line naming it. Writing is atomic (``utils.atomic``).
"""
from __future__ import annotations

import json
import tokenize
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.library.grounded import valid_findings
from motionlang.library.scan import take_name
from motionlang.utils import limits
from motionlang.utils.atomic import atomic_write
from motionlang.utils.sidecar import parse_json

WHAT = "motionlang index"
#: 1: no findings; 2: findings; 3: each entry's ``declared_fps`` (an older motionlang names
#: the newer format rather than an unknown field)
FORMAT = 3


@dataclass
class Entry:
    """One take of the index and its windows' rows (``rows`` of them, in order), and the
    analysis' findings (None: not analysed, an index of format 1)."""

    path: str
    size: int
    mtime: float
    sha256: str
    rig: dict
    fps: float
    duration: float
    rows: int
    sequence: int = 1
    sequences: int = 1
    findings: list[dict] | None = None
    #: the header's rate where the take was read at the one its body says (``fps``)
    declared_fps: float | None = None

    @property
    def name(self) -> str:
        """The take as hits name it (``scan.take_name``)."""
        return take_name(self.path, self.sequence, self.sequences)


@dataclass
class Failure:
    """A file that was skipped, and why (one line)."""

    path: str
    size: int
    mtime: float
    sha256: str
    reason: str


@dataclass
class IndexData:
    """An index in memory: what the file holds (see the module docstring)."""

    model: dict
    root: str
    window: float
    hop: float
    entries: list[Entry] = field(default_factory=list)
    failed: list[Failure] = field(default_factory=list)
    vectors: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.float32))
    spans: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    analysis: int = 0
    shard: str = ""   # "K/N" for a shard of a folder (``index --shard``), "" for all of it

    @property
    def first_rows(self) -> np.ndarray:
        """(len(entries) + 1,) the first row of each entry, then the row count."""
        return np.concatenate([[0], np.cumsum([e.rows for e in self.entries])]).astype(int)

    def entry_of_rows(self) -> np.ndarray:
        """(N,) the entry each row belongs to."""
        return np.repeat(np.arange(len(self.entries)), [e.rows for e in self.entries])

    def meta(self) -> dict:
        return {"what": WHAT, "format": FORMAT, "model": self.model, "root": self.root,
                "window": self.window, "hop": self.hop, "analysis": self.analysis,
                "shard": self.shard,
                "entries": [asdict(e) for e in self.entries],
                "failed": [asdict(f) for f in self.failed]}


def save_index(data: IndexData, path: str | Path) -> Path:
    """Write ``data`` to ``path`` atomically (uncompressed: it loads fastest)."""
    path = Path(path)
    with atomic_write(path, "wb") as fh:
        np.savez(fh, vectors=np.asarray(data.vectors, dtype=np.float32),
                 spans=np.asarray(data.spans, dtype=np.float64),
                 meta=np.array(json.dumps(data.meta())))
    return path


def _damaged(path: Path, why: str) -> MotionlangError:
    return MotionlangError(f"{path}: not a readable motionlang index ({why}); make it again "
                           "with 'motionlang index DIR -o FILE --rebuild'")


def _arrays(path: Path) -> dict[str, np.ndarray]:
    """The three arrays of an index file, their sizes checked before they are read."""
    try:
        with zipfile.ZipFile(path) as zf:
            infos = {i.filename: i for i in zf.infolist()}
    except (OSError, zipfile.BadZipFile, ValueError, NotImplementedError) as exc:
        raise _damaged(path, f"not an npz archive: {exc}") from None
    names = {"vectors.npy", "spans.npy", "meta.npy"}
    if set(infos) != names:
        raise _damaged(path, f"a zip archive of {len(infos)} members, not of "
                             f"{', '.join(sorted(names))}")
    limits.check(path, "max_memory_bytes", sum(i.file_size for i in infos.values()),
                 "memory needed to read the index")
    try:
        with zipfile.ZipFile(path) as zf:
            for name in sorted(names):   # what each header declares, before numpy makes it
                declared = _declared_bytes(zf, name)
                if declared > infos[name].file_size:
                    raise _damaged(path, f"{name} declares {declared:,} bytes of data but "
                                         f"holds {infos[name].file_size:,}")
        with np.load(path, allow_pickle=False) as npz:
            out = {k: npz[k] for k in ("vectors", "spans", "meta")}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, SyntaxError,
            tokenize.TokenError, OverflowError, NotImplementedError) as exc:
        # a garbled .npy header, a size beyond C's, a zip flag numpy does not read
        raise _damaged(path, f"an array does not read: {exc}") from None
    for k, v in out.items():   # numpy gives the raw bytes of a member that is no .npy
        if not isinstance(v, np.ndarray):
            raise _damaged(path, f"{k}.npy is not an array")
    return out


def _declared_bytes(zf: zipfile.ZipFile, name: str) -> int:
    """The bytes of data the ``.npy`` header of member ``name`` declares (0 where the
    header does not read: numpy names that itself)."""
    try:
        with zf.open(name) as fh:
            version = np.lib.format.read_magic(fh)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) \
                else np.lib.format.read_array_header_2_0
            shape, _, dtype = read(fh)
    except (OSError, ValueError, EOFError, SyntaxError, TypeError, zipfile.BadZipFile):
        return 0
    return int(np.prod(shape, dtype=object)) * dtype.itemsize


#: what each field of an entry must be (bool is no int here)
_ENTRY_TYPES: dict[str, tuple[type, ...]] = {
    "path": (str,), "size": (int,), "mtime": (int, float), "sha256": (str,), "rig": (dict,),
    "fps": (int, float), "duration": (int, float), "rows": (int,), "sequence": (int,),
    "sequences": (int,), "findings": (list, type(None)),
    "declared_fps": (int, float, type(None))}
_FAILURE_TYPES: dict[str, tuple[type, ...]] = {
    "path": (str,), "size": (int,), "mtime": (int, float), "sha256": (str,), "reason": (str,)}


def _typed(item: Any, types: dict[str, tuple[type, ...]], what: str) -> dict:
    """``item`` (a dict of metadata) if each field it has is of its type, else a
    ValueError naming the first that is not."""
    if not isinstance(item, dict):
        raise ValueError(f"{what} is {type(item).__name__}, not an object")
    for key, value in item.items():
        kinds = types.get(key)
        if kinds is None:
            raise ValueError(f"{what} has an unknown field {key!r}")
        if isinstance(value, bool) or not isinstance(value, kinds):
            raise ValueError(f"{what}.{key} is {type(value).__name__}: {str(value)[:40]!r}")
    return item


def load_index(path: str | Path) -> IndexData:
    """The index in ``path``, every part checked against the others.

    Raises:
        MotionlangError: one line naming the file: missing, damaged, foreign, or written
            by a newer motionlang.
    """
    path = Path(path)
    if not path.is_file():
        raise MotionlangError(f"{path}: no such index file (make one with 'motionlang index "
                              "DIR -o FILE')")
    a = _arrays(path)
    vectors, spans, meta = a["vectors"], a["spans"], a["meta"]
    if meta.shape != () or meta.dtype.kind != "U":
        raise _damaged(path, "no metadata string")
    try:
        m = parse_json(str(meta), "metadata")
    except MotionlangError as exc:
        raise _damaged(path, str(exc)) from None
    if not isinstance(m, dict) or m.get("what") != WHAT:
        raise _damaged(path, "no motionlang index metadata")
    fmt = m.get("format")
    if isinstance(fmt, bool) or not isinstance(fmt, int) or fmt < 1:
        raise _damaged(path, f"index format {str(fmt)[:20]!r} is not one motionlang writes")
    if fmt > FORMAT:
        raise MotionlangError(f"{path}: index format {fmt} is newer than this motionlang "
                              f"reads ({FORMAT}); upgrade motionlang")
    try:
        model = m["model"]
        if not isinstance(model, dict) or not isinstance(model.get("name"), str):
            raise ValueError("its model has no name")
        if not isinstance(m["entries"], list) or not isinstance(m["failed"], list):
            raise ValueError("entries and failed must be lists")
        data = IndexData(model=dict(model), root=str(m["root"]),
                         window=float(m["window"]), hop=float(m["hop"]),
                         entries=[Entry(**_typed(e, _ENTRY_TYPES, f"entry {i}"))
                                  for i, e in enumerate(m["entries"])],
                         failed=[Failure(**_typed(f, _FAILURE_TYPES, f"failed {i}"))
                                 for i, f in enumerate(m["failed"])], vectors=vectors,
                         spans=spans, analysis=int(m.get("analysis", 0)),
                         shard=str(m.get("shard", "")))
    except (KeyError, TypeError, ValueError) as exc:
        raise _damaged(path, f"malformed metadata: {exc}") from None
    n = int(data.first_rows[-1])
    if vectors.ndim != 2 or vectors.dtype != np.float32 or len(vectors) != n:
        raise _damaged(path, f"vectors {vectors.shape} {vectors.dtype}, expected ({n}, D) "
                             "float32")
    if spans.shape != (n, 2) or spans.dtype.kind != "f":
        raise _damaged(path, f"spans {spans.shape} {spans.dtype}, expected ({n}, 2) float")
    if n and not (np.isfinite(vectors).all() and np.isfinite(spans).all()):
        raise _damaged(path, "non-finite values")
    if any(e.rows < 0 for e in data.entries):
        raise _damaged(path, "a negative window count")
    if any(e.findings is not None and not valid_findings(e.findings) for e in data.entries):
        raise _damaged(path, "malformed findings")
    return data

"""Build or bring up to date the index of a folder of motion files.

Every file a reader knows (``formats``), of any rig the 21-joint body maps, is cut into
overlapping windows (:mod:`.windows`) and each window embedded by a model that puts
sentences and motions in one space (:mod:`.embedder`). A second run reads the files'
digests and embeds only what is new or changed; files gone are dropped. A file that does
not read is listed with its one-line reason and skipped: one bad file never ends a run.
Every take is also analysed (:mod:`.grounded`), and the findings stored with it; a take
of an older index that holds none is read and analysed again, its vectors kept.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.analysis import VERSION as ANALYSIS
from motionlang.errors import MotionlangError
from motionlang.library.embedder import Embedder
from motionlang.library.grounded import take_findings
from motionlang.library.options import IndexOptions
from motionlang.library.scan import file_facts, motion_files, read_takes, reason, rig_of
from motionlang.library.store import Entry, Failure, IndexData, load_index, save_index
from motionlang.library.windows import motion_windows, span


@dataclass
class IndexSummary:
    """What a run of :func:`build_index` did.

    Attributes:
        index: the index file written.
        model: the model's name.
        files: files in the index (readable ones); ``takes`` and ``windows`` in them;
            ``hours`` of motion.
        embedded: files embedded by this run; ``reused``: files whose digest the index
            already held; ``removed``: files of the old index no longer in the folder;
            ``analysed``: reused files analysed anew (their findings missing, or made
            by other detectors: ``analysis.VERSION``).
        vectors: windows embedded by this run.
        failed: ``[(path, reason)]`` of the files skipped.
        seconds: wall time of the run.
    """

    index: str
    model: str
    files: int = 0
    takes: int = 0
    windows: int = 0
    hours: float = 0.0
    embedded: int = 0
    reused: int = 0
    removed: int = 0
    analysed: int = 0
    vectors: int = 0
    failed: list[tuple[str, str]] = field(default_factory=list)
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["failed"] = [{"path": p, "reason": r} for p, r in self.failed]
        return d

    def text(self) -> str:
        """A few lines for a person (the skipped files are listed apart)."""
        return (f"{self.index}: {self.files} files, {self.takes} takes, {self.windows} "
                f"windows, {self.hours:.2f} h of motion ({self.model})\n"
                f"  this run: {self.embedded} files embedded ({self.vectors} windows), "
                f"{self.reused} unchanged"
                + (f" ({self.analysed} analysed anew)" if self.analysed else "")
                + f", {self.removed} removed, {len(self.failed)} skipped, {self.seconds:.1f} s")


def embed_take(embedder: Embedder, motion, window: float, hop: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """(vectors (n, D) float32, spans (n, 2) seconds) of the windows of one take."""
    pairs = motion_windows(motion, window, hop)
    vectors = np.stack([embedder.motion(m) for _, m in pairs])
    return vectors, np.array([(w.start, w.end) for w, _ in pairs], dtype=np.float64)


class _Builder:
    """The new index as it grows, and what the old one offers to reuse."""

    def __init__(self, old: IndexData | None, data: IndexData, rebuild: bool):
        self.data = data
        self.blocks: list[tuple[np.ndarray, np.ndarray]] = []
        self.takes: dict[str, list[tuple[Entry, np.ndarray, np.ndarray]]] = {}
        self.bad: dict[str, Failure] = {}
        if old is not None and not rebuild:
            first = old.first_rows
            for i, e in enumerate(old.entries):
                rows = slice(first[i], first[i + 1])
                if old.analysis != ANALYSIS:   # findings of other detectors: made anew
                    e = Entry(**{**asdict(e), "findings": None})
                self.takes.setdefault(e.sha256, []).append((e, old.vectors[rows],
                                                            old.spans[rows]))
            self.bad = {f.sha256: f for f in old.failed if f.sha256}
        self.old_paths = {e.path for e in old.entries} | {f.path for f in old.failed} \
            if old is not None else set()
        self.used: set[str] = set()

    def add(self, entry: Entry, vectors: np.ndarray, spans: np.ndarray) -> None:
        self.data.entries.append(entry)
        self.blocks.append((vectors, spans))

    def snapshot(self, final: bool) -> IndexData:
        """The index so far; before the end, the old takes not yet met are kept too, so
        that an interrupted run loses none of them."""
        d = self.data
        entries, blocks = list(d.entries), list(self.blocks)
        if not final:
            for digest, takes in self.takes.items():
                if digest not in self.used:
                    entries += [e for e, _, _ in takes]
                    blocks += [(v, s) for _, v, s in takes]
        dim = next((v.shape[1] for v, _ in blocks if v.size), 0)
        vectors = np.concatenate([v for v, _ in blocks]) if blocks else np.zeros((0, dim))
        spans = np.concatenate([s for _, s in blocks]) if blocks else np.zeros((0, 2))
        return IndexData(d.model, d.root, d.window, d.hop, entries, list(d.failed),
                         vectors.astype(np.float32), spans, d.analysis)


def _open_old(out: Path, embedder: Embedder, opts: IndexOptions) -> IndexData | None:
    """The index already in ``out``, checked to be of this model and these windows."""
    if opts.rebuild or not out.exists():
        return None
    old = load_index(out)
    again = "; pass --rebuild (rebuild=True) to embed the folder anew"
    try:
        embedder.check(old.model, str(out))
    except MotionlangError as exc:
        raise MotionlangError(f"{exc}{again}") from None
    if (old.window, old.hop) != (opts.window, opts.hop):
        raise MotionlangError(f"{out}: made with windows of {old.window:g} s every "
                              f"{old.hop:g} s, not {opts.window:g} s every {opts.hop:g} s"
                              f"{again}")
    return old


def build_index(folder: str | Path, out: str | Path, model: Any = None,
                **options: Any) -> IndexSummary:
    """Index every motion file under ``folder`` into ``out`` (made, or brought up to date).

    model: a packaged name, a checkpoint file or run folder, a loaded model or an
    :class:`~motionlang.library.embedder.Embedder` whose family encodes sentences and
    motions (default: ``embedder.DEFAULT_MODEL``). options: the fields of
    :class:`~motionlang.library.options.IndexOptions` (``window``, ``hop``, ``rebuild``).

    Raises:
        MotionlangError: a bad option, a missing folder, a model that does not encode both
            sides, or an existing index of another model or other windows (without
            ``rebuild``); never for a file of the folder, which is listed and skipped.
    """
    from motionlang.utils.progress import progress
    t0 = time.perf_counter()
    opts = IndexOptions(**options)
    root, out = Path(folder).resolve(), Path(out)
    paths = motion_files(root)
    embedder = Embedder.load(model)
    old = _open_old(out, embedder, opts)
    data = IndexData(embedder.identity, str(root), opts.window, opts.hop, analysis=ANALYSIS)
    b = _Builder(old, data, opts.rebuild)
    summary = IndexSummary(str(out), embedder.name)
    last_save = time.monotonic()
    bar = progress(total=len(paths), desc="index", unit="files",
                   disable=None if opts.show_progress is None else not opts.show_progress)
    with bar:
        for path in paths:
            rel = path.relative_to(root).as_posix()
            _index_file(b, summary, embedder, root, path, rel, opts)
            bar.update(1)
            if time.monotonic() - last_save >= opts.save_every:
                save_index(b.snapshot(final=False), out)
                last_save = time.monotonic()
    final = b.snapshot(final=True)
    save_index(final, out)
    summary.files = len({e.path for e in final.entries})
    summary.takes, summary.windows = len(final.entries), len(final.vectors)
    summary.hours = sum(e.duration for e in final.entries) / 3600.0
    here = {e.path for e in final.entries} | {f.path for f in final.failed}
    summary.removed = len(b.old_paths - here)
    summary.failed = [(f.path, f.reason) for f in final.failed]
    summary.seconds = time.perf_counter() - t0
    return summary


def _index_file(b: _Builder, summary: IndexSummary, embedder: Embedder, root: Path,
                path: Path, rel: str, opts: IndexOptions) -> None:
    """Add one file to the index: reused by its digest, or read and embedded, or listed as
    skipped with its reason."""
    try:
        facts = file_facts(root, path)
    except MotionlangError as exc:
        b.data.failed.append(Failure(rel, 0, 0.0, "", reason(exc, path, rel)))
        return
    stamp = {"path": rel, "size": facts.size, "mtime": facts.mtime}
    if facts.sha256 in b.takes:
        b.used.add(facts.sha256)
        old = b.takes[facts.sha256]
        found: list[list[dict] | None] = [e.findings for e, _, _ in old]
        if any(f is None for f in found):
            found = list(_analysed(path, len(old)))
            summary.analysed += 1
        for (e, v, s), f in zip(old, found):
            b.add(Entry(**{**asdict(e), **stamp, "findings": f}), v, s)
        summary.reused += 1
        return
    if facts.sha256 in b.bad:
        b.data.failed.append(Failure(**{**asdict(b.bad[facts.sha256]), **stamp}))
        return
    try:
        takes = read_takes(path)
        done = []
        for i, motion in enumerate(takes, 1):
            rig = rig_of(motion)   # a rig no map fits fails before any embedding
            vectors, spans = embed_take(embedder, motion, opts.window, opts.hop)
            done.append((Entry(rel, facts.size, facts.mtime, facts.sha256, rig,
                               float(motion.fps), float(span(motion)), len(vectors), i,
                               len(takes), take_findings(motion)), vectors, spans))
    except Exception as exc:   # noqa: BLE001 (one file's failure, whatever it is, is its own)
        b.data.failed.append(Failure(rel, facts.size, facts.mtime, facts.sha256,
                                     reason(exc, path, rel)))
        return
    for entry, vectors, spans in done:
        b.add(entry, vectors, spans)
        summary.vectors += len(vectors)
    summary.embedded += 1


def _analysed(path: Path, takes: int) -> list[list[dict]]:
    """The findings of each of a file's ``takes`` (an entry of an older index reused):
    ``[]`` each where the file no longer reads as it did."""
    try:
        motions = read_takes(path)
    except MotionlangError:
        motions = []
    if len(motions) != takes:
        return [[] for _ in range(takes)]
    return [take_findings(m) for m in motions]

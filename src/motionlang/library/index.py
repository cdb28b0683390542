"""Build or bring up to date the index of a folder of motion files.

Every file a reader knows (``formats``), of any rig the 21-joint body maps, is cut into
overlapping windows (:mod:`.windows`) and each window embedded by a model that puts
sentences and motions in one space (:mod:`.embedder`). A second run reads the files'
digests and embeds only what is new or changed; files gone are dropped. A file that does
not read is listed with its one-line reason and skipped: one bad file never ends a run.
Every take is also analysed (:mod:`.grounded`), and the findings stored with it; a take
of an older index that holds none is read and analysed again, its vectors kept. The files
of one export (a folder's BVH files of one rig and declared rate, ``library.rates``) are
read at one rate, as ``describe DIR`` reads them: every export that holds a file of the
run is judged whole on every run (the other shards' files too), and an unchanged take of
such an export read at another rate before is embedded anew.
"""
from __future__ import annotations

import hashlib
import os
import pickle
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.analysis import VERSION as ANALYSIS
from motionlang.errors import MotionlangError
from motionlang.library.embedder import Embedder
from motionlang.library.grounded import take_findings
from motionlang.library.options import IndexOptions, shard_of
from motionlang.library.rates import SharedRate, shared_rates
from motionlang.library.ray_engine import embedded_on_ray
from motionlang.library.scan import file_facts, motion_files, read_takes, reason, rig_of
from motionlang.library.store import Entry, Failure, IndexData, load_index, save_index
from motionlang.library.windows import motion_windows, span
from motionlang.utils.progress import progress

#: takes named in the summary's line about the takes read at their bodies' rate
RETIMED_SHOWN = 5


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
        retimed: ``[(take, declared Hz, read Hz)]`` of the takes embedded by this run at
            the rate their bodies say rather than their header's (``analysis.rate``), or
            their export's (``library.rates``).
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
    retimed: list[tuple[str, float, float]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["failed"] = [{"path": p, "reason": r} for p, r in self.failed]
        d["retimed"] = [{"take": t, "declared_fps": a, "fps": b} for t, a, b in self.retimed]
        return d

    def text(self) -> str:
        """A few lines for a person (the skipped files are listed apart)."""
        return (f"{self.index}: {self.files} files, {self.takes} takes, {self.windows} "
                f"windows, {self.hours:.2f} h of motion ({self.model})\n"
                f"  this run: {self.embedded} files embedded ({self.vectors} windows), "
                f"{self.reused} unchanged"
                + (f" ({self.analysed} analysed anew)" if self.analysed else "")
                + f", {self.removed} removed, {len(self.failed)} skipped, {self.seconds:.1f} s"
                + (f"\n  {len(self.retimed)} read at the rate their bodies (or their "
                   "export's) say, not their header's (analysis.rate, library.rates): " + ", ".join(
                       f"{t} ({a:g} -> {b:g} Hz)" for t, a, b in self.retimed[:RETIMED_SHOWN])
                   + (", ..." if len(self.retimed) > RETIMED_SHOWN else "")
                   if self.retimed else ""))


def embed_take(embedder: Embedder, motion, window: float, hop: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """(vectors (n, D) float32, spans (n, 2) seconds) of the windows of one take."""
    pairs = motion_windows(motion, window, hop)
    vectors = np.stack([embedder.motion(m) for _, m in pairs])
    return vectors, np.array([(w.start, w.end) for w, _ in pairs], dtype=np.float64)


class _Builder:
    """The new index as it grows, and what the old one offers to reuse."""

    def __init__(self, old: IndexData | None, data: IndexData):
        self.data = data
        self.blocks: list[tuple[np.ndarray, np.ndarray]] = []
        self.order: list[int] = []     # each entry's file's place in the folder's listing
        self.failed_at: list[int] = []
        #: the old index's takes by digest, then by the file they were read from (copies
        #: of one file at several paths hold one digest: each path keeps its own takes)
        self.takes: dict[str, dict[str, list[tuple[Entry, np.ndarray, np.ndarray]]]] = {}
        self.bad: dict[str, Failure] = {}
        if old is not None:
            first = old.first_rows
            for i, e in enumerate(old.entries):
                rows = slice(first[i], first[i + 1])
                if old.analysis != ANALYSIS:   # findings of other detectors: made anew
                    # (and the take embedded anew where it now reads at another rate,
                    # ``_analysed``: the rate check is the analysis' too)
                    e = Entry(**{**asdict(e), "findings": None})
                mine = self.takes.setdefault(e.sha256, {}).setdefault(e.path, [])
                if all(t.sequence != e.sequence for t, _, _ in mine):   # an older
                    # motionlang gave each copy of a file every copy's takes: kept once
                    mine.append((e, old.vectors[rows], old.spans[rows]))
            self.bad = {f.sha256: f for f in old.failed if f.sha256}
        self.old_paths = {e.path for e in old.entries} | {f.path for f in old.failed} \
            if old is not None else set()
        self.used: set[tuple[str, str]] = set()   # (digest, old path) of the takes reused

    def reusable(self, digest: str, rel: str) -> list[tuple[Entry, np.ndarray, np.ndarray]]:
        """The old takes a file of ``digest`` at ``rel`` reuses: its own where the old
        index had this path, else those of a copy at another path ([] where none)."""
        paths = self.takes.get(digest, {})
        return paths.get(rel) or next(iter(paths.values()), [])

    def add(self, entry: Entry, vectors: np.ndarray, spans: np.ndarray, at: int) -> None:
        self.data.entries.append(entry)
        self.blocks.append((vectors, spans))
        self.order.append(at)

    def fail(self, failure: Failure, at: int) -> None:
        self.data.failed.append(failure)
        self.failed_at.append(at)

    def snapshot(self, final: bool) -> IndexData:
        """The index so far, in the folder's order whatever order files were done in;
        before the end, the old takes not yet met are kept too, so that an interrupted run
        loses none of them."""
        d = self.data
        rank = sorted(range(len(d.entries)), key=lambda i: self.order[i])
        entries, blocks = [d.entries[i] for i in rank], [self.blocks[i] for i in rank]
        failed = [d.failed[i] for i in sorted(range(len(d.failed)),
                                              key=lambda i: self.failed_at[i])]
        if not final:
            for digest, paths in self.takes.items():
                for path, takes in paths.items():
                    if (digest, path) not in self.used:
                        entries += [e for e, _, _ in takes]
                        blocks += [(v, s) for _, v, s in takes]
        dim = next((v.shape[1] for v, _ in blocks if v.size), 0)
        vectors = np.concatenate([v for v, _ in blocks]) if blocks else np.zeros((0, dim))
        spans = np.concatenate([s for _, s in blocks]) if blocks else np.zeros((0, 2))
        return IndexData(d.model, d.root, d.window, d.hop, entries, failed,
                         vectors.astype(np.float32), spans, d.analysis, d.shard)


def in_shard(rel: str, k: int, n: int) -> bool:
    """Whether the file at ``rel`` (under the folder) belongs to shard ``k`` of ``n``: by
    the hash of its path, the same on every machine."""
    return int(hashlib.sha256(rel.encode("utf-8")).hexdigest()[:8], 16) % n == k - 1


def _open_old(out: Path, embedder: Embedder, opts: IndexOptions, root: Path
              ) -> IndexData | None:
    """The index already in ``out``, checked to be of this folder, model and windows."""
    if opts.rebuild or not out.exists():
        return None
    old = load_index(out)
    again = "; pass --rebuild (rebuild=True) to embed the folder anew"
    if old.root != str(root):
        raise MotionlangError(f"{out}: the index of {old.root}, not of {root}: give another "
                              f"-o for this folder, or pass --rebuild to replace it")
    try:
        embedder.check(old.model, str(out))
    except MotionlangError as exc:
        raise MotionlangError(f"{exc}{again}") from None
    if old.shard != (opts.shard or ""):
        was = f"shard {old.shard}" if old.shard else "the whole folder"
        now = f"shard {opts.shard}" if opts.shard else "the whole folder"
        raise MotionlangError(f"{out}: made of {was}, not of {now}{again}")
    if (old.window, old.hop) != (opts.window, opts.hop):
        raise MotionlangError(f"{out}: made with windows of {old.window:g} s every "
                              f"{old.hop:g} s, not {opts.window:g} s every {opts.hop:g} s"
                              f"{again}")
    return old


def _open_partial(partial: Path, embedder: Embedder, opts: IndexOptions) -> IndexData | None:
    """What an interrupted rebuild had done (``OUT.rebuilding``), where it is of this model,
    windows and shard; None (and nothing kept of it) otherwise."""
    if not partial.exists():
        return None
    try:
        old = load_index(partial)
        embedder.check(old.model, str(partial))
    except MotionlangError:
        return None
    if (old.window, old.hop, old.shard) != (opts.window, opts.hop, opts.shard or ""):
        return None
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
    t0 = time.perf_counter()
    opts = IndexOptions(**options)
    root, out = Path(folder).resolve(), Path(out)
    unlisted: list[tuple[str, str]] = []
    paths = every = motion_files(root, unlisted)
    if not every and not unlisted and not out.exists():   # a mistyped folder (an index
        # made before may be emptied: its files were removed)
        raise MotionlangError(f"{folder}: no motion files under it (.bvh, .amc with its "
                              ".asf, .xml MMM, .mat, DeepMimic .txt): nothing indexed")
    if opts.shard:
        k, n = shard_of(opts.shard)
        paths = [p for p in paths if in_shard(p.relative_to(root).as_posix(), k, n)]
    embedder = Embedder.load(model)
    # a rebuild saves as it goes beside the index, which it replaces only once complete: an
    # interrupted rebuild loses nothing, and the next one goes on from what it had done
    partial = out.with_name(out.name + ".rebuilding") if opts.rebuild else None
    old = _open_old(out, embedder, opts, root) if partial is None else _open_partial(
        partial, embedder, opts)
    data = IndexData(embedder.identity, str(root), opts.window, opts.hop, analysis=ANALYSIS,
                     shard=opts.shard or "")
    b = _Builder(old, data)
    for at, (rel, why) in enumerate(unlisted):
        b.fail(Failure(rel, 0, 0.0, "", why), -1 - at)
    summary = IndexSummary(str(out), embedder.name)
    last_save = time.monotonic()
    hide = None if opts.show_progress is None else not opts.show_progress
    known = [(at, path, path.relative_to(root).as_posix()) for at, path in enumerate(paths)]
    facts = [_facts(b, root, path, rel, at) for at, path, rel in progress(
        known, desc="digests", unit="files", disable=hide)]
    # one export, one rate (library.rates): every export of this run's files judged whole,
    # the files of other shards too, on every run, so that every shard reads them alike
    # and a file come or gone moves the rest of its export with it
    exports = shared_rates(every, only=paths, show_progress=opts.show_progress) \
        if paths else {}
    bar = progress(total=len(paths), desc="index", unit="files", disable=hide)
    with bar:
        todo = []
        for (at, path, rel), f in zip(known, facts):
            export = exports.get(str(path))
            if f is not None and _known(b, summary, path, rel, at, f, export,
                                        judged=str(path) in exports):
                todo.append(_Job(at, path, rel, f, opts.window, opts.hop, export))
            else:
                bar.update(1)
        if opts.engine == "ray":
            sent = model if isinstance(model, (str, Path)) or model is None else embedder
            done = embedded_on_ray(todo, sent, opts.workers, embed_file) if todo else iter(())
        else:
            done = _embedded(todo, embedder, model, opts.workers)
        try:
            for job, result in done:
                _add(b, summary, job, result)
                bar.update(1)
                if time.monotonic() - last_save >= opts.save_every:
                    save_index(b.snapshot(final=False), partial or out)
                    last_save = time.monotonic()
        except (MotionlangError, KeyboardInterrupt):   # a dead worker, Ctrl-C: keep the work
            if summary.embedded:
                save_index(b.snapshot(final=False), partial or out)
            raise
    final = b.snapshot(final=True)
    save_index(final, out)
    if partial is not None:
        partial.unlink(missing_ok=True)
    summary.files = len({e.path for e in final.entries})
    summary.takes, summary.windows = len(final.entries), len(final.vectors)
    summary.hours = sum(e.duration for e in final.entries) / 3600.0
    here = {e.path for e in final.entries} | {f.path for f in final.failed}
    summary.removed = len(b.old_paths - here)
    summary.failed = [(f.path, f.reason) for f in final.failed]
    summary.seconds = time.perf_counter() - t0
    return summary


@dataclass(frozen=True)
class _Job:
    """A file to read, analyse and embed: its place in the listing, path, facts, windows."""

    at: int
    path: Path
    rel: str
    facts: Any
    window: float
    hop: float
    export: SharedRate | None = None


def _facts(b: _Builder, root: Path, path: Path, rel: str, at: int):
    """The file's facts (size, time, digest), or None where it cannot be read (listed as
    failed)."""
    try:
        return file_facts(root, path)
    except MotionlangError as exc:
        b.fail(Failure(rel, 0, 0.0, "", reason(exc, path, rel)), at)
        return None


def _known(b: _Builder, summary: IndexSummary, path: Path, rel: str, at: int, facts,
           export: SharedRate | None, *, judged: bool) -> bool:
    """Whether the file must be embedded; where not, its entries (reused by its digest) or
    its failure (skipped again for the reason it had) are settled. ``export``: the rate
    its export is read at (``library.rates.shared_rates``) where ``judged``; a reused take
    read at another rate is embedded anew."""
    stamp = {"path": rel, "size": facts.size, "mtime": facts.mtime}
    if facts.sha256 in b.takes:
        old = b.reusable(facts.sha256, rel)
        found: list[list[dict] | None] = [e.findings for e, _, _ in old]
        rates = [e.fps for e, _, _ in old]
        stale = judged and (any(abs(r - export.rate) > 1e-6 * r for r in rates)
                            if export is not None
                            else any(e.declared_fps is not None for e, _, _ in old))
        if stale or any(f is None for f in found):
            again = _analysed(path, [(e.fps, e.duration) for e, _, _ in old], export)
            if again is None:   # read at another rate now (analysis.rate): its windows too
                paths = b.takes[facts.sha256]   # its own not kept beside the new ones by a
                if paths.get(rel) is old:       # save (a copy's stay the copy's)
                    del paths[rel]
                    if not paths:
                        del b.takes[facts.sha256]
                return True
            found = list(again)
            summary.analysed += 1
        b.used.add((facts.sha256, old[0][0].path))
        for (e, v, s), f in zip(old, found):
            b.add(Entry(**{**asdict(e), **stamp, "findings": f}), v, s, at)
        summary.reused += 1
        return False
    if facts.sha256 in b.bad:
        b.fail(Failure(**{**asdict(b.bad[facts.sha256]), **stamp}), at)
        return False
    return True


def embed_file(embedder: Embedder, job: _Job) -> list[tuple[Entry, np.ndarray, np.ndarray]] | str:
    """A file's takes as (entry, vectors, spans), or the one-line reason it is skipped."""
    f = job.facts
    try:
        takes = read_takes(job.path, job.export)
        done = []
        for i, motion in enumerate(takes, 1):
            rig = rig_of(motion)   # a rig no map fits fails before any embedding
            vectors, spans = embed_take(embedder, motion, job.window, job.hop)
            declared = motion.meta.get("declared_fps")
            done.append((Entry(job.rel, f.size, f.mtime, f.sha256, rig, float(motion.fps),
                               float(span(motion)), len(vectors), i, len(takes),
                               take_findings(motion),
                               None if declared is None else float(declared)),
                         vectors, spans))
    except Exception as exc:   # noqa: BLE001 (one file's failure, whatever it is, is its own)
        return reason(exc, job.path, job.rel)
    return done


def _add(b: _Builder, summary: IndexSummary, job: _Job, result) -> None:
    f = job.facts
    if isinstance(result, str):
        b.fail(Failure(job.rel, f.size, f.mtime, f.sha256, result), job.at)
        return
    for entry, vectors, spans in result:
        b.add(entry, vectors, spans, job.at)
        summary.vectors += len(vectors)
        if entry.declared_fps is not None:
            summary.retimed.append((entry.name, entry.declared_fps, entry.fps))
    summary.embedded += 1


_WORKER: Embedder | None = None


def _start_worker(model: Any, threads: int) -> None:
    """A worker process: the model loaded once."""
    global _WORKER
    import torch
    torch.set_num_threads(threads)
    _WORKER = Embedder.load(model)


def _worker_embed(job: _Job):
    assert _WORKER is not None, "worker not started"
    return job, embed_file(_WORKER, job)


def _embedded(jobs: list[_Job], embedder: Embedder, model: Any, workers: int):
    """``(job, result)`` of each job, in order: here, or in ``workers`` processes (at most
    the CPU count and the jobs), each loading the model once."""
    workers = max(1, min(workers, os.cpu_count() or 1, len(jobs)))
    if workers == 1:
        for job in jobs:
            yield job, embed_file(embedder, job)
        return
    import multiprocessing

    import torch
    sent = model if isinstance(model, (str, Path)) or model is None else embedder
    try:
        pickle.dumps(sent)
    except Exception:   # noqa: BLE001 (whatever stops it from being sent, the answer is one)
        raise MotionlangError("--workers needs a model given by name or file (this one "
                              "cannot be sent to other processes)") from None
    threads = max(1, torch.get_num_threads() // workers)
    # spawned, not forked: a fork of a process whose torch runs threads can hang
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(workers, mp_context=ctx, initializer=_start_worker,
                             initargs=(sent, threads)) as pool:
        try:
            yield from pool.map(_worker_embed, jobs)
        except BrokenProcessPool:
            raise MotionlangError("an index worker process died (killed, or out of "
                                  "memory); what was embedded before is kept in the index: "
                                  "run the same command again to go on") from None


def _analysed(path: Path, read: list[tuple[float, float]], export: SharedRate | None = None
              ) -> list[list[dict]] | None:
    """The findings of each take of a file whose entries an older index made, read at the
    rate and for the span ``read`` gives each (Hz, s): ``[]`` each where the file no
    longer reads as it did; None where it now reads at another rate (the rate check
    changed, or the rate of its ``export``) or for another span (a reader now leaves out
    frames that are not the take's, ``kinematics.reference_pose``): its windows are
    embedded anew."""
    try:
        motions = read_takes(path, export)
    except MotionlangError:
        motions = []
    if len(motions) != len(read):
        return [[] for _ in read]
    if any(abs(m.fps - r) > 1e-6 * r or abs(span(m) - d) > 0.5 / m.fps
           for m, (r, d) in zip(motions, read)):
        return None
    return [take_findings(m) for m in motions]

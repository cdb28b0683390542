"""Describing a whole library: many files in one process (the model loaded once, or once per
worker process), long takes as timelines, and sentences from a bank instead of a model's own.

Each file gives one record, a dict that is also its JSON line::

    {"file": "takes/walk.bvh", "sentences": [{"text": "a person walks", "log_p": -3.2}, ...]}
    {"file": "takes/long.bvh", "segments": [{"start": 0.0, "end": 4.0, "text": ...,
                                            "log_p": ...}, ...]}
    {"file": "takes/broken.bvh", "error": "takes/broken.bvh:12: ..."}

A bank's scores are cosines (``"cos"``), a model's log probabilities (``"log_p"``); scores are
rounded to 4 decimals so that records compare equal whatever process or thread count made
them. A file that cannot be read or described is a record with its reason, never the end of
the run.
"""
from __future__ import annotations

import copy
import json
import math
import os
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from motionlang.analysis import analyse
from motionlang.analysis.rate import at_its_rate, read_at
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import match_rig
from motionlang.formats import read_motion
from motionlang.library.bank import SentenceBank, default_bank_model, embed_bank, read_bank
from motionlang.library.embedder import Embedder
from motionlang.library.options import DescribeOptions
from motionlang.library.rates import SharedRate, at_export_rate, shared_rates
from motionlang.library.scan import motion_files
from motionlang.library.timeline import Segment, merge_windows
from motionlang.library.windows import Window, cut, motion_windows, span
from motionlang.models.registry import describer as family_describer
from motionlang.models.registry import kinds_with, load_model, resolve
from motionlang.utils.atomic import atomic_write
from motionlang.utils.progress import progress

#: a take at least this long (seconds of motion) shows the progress of its timeline
LONG_TAKE_S = 600.0


@dataclass(frozen=True)
class ReadOptions:
    """How files are read: the ``read_motion`` options that apply to some formats only
    (``skeleton``: AMC; ``sequence``: MAT), ``fps`` (AMC's rate, or the rate that replaces
    any other file's own), and a joint map for every file; ``shared``: the rates of exports
    that declare a wrong one (``library.rates.shared_rates``, by path; None: its export was
    judged right), where ``fps`` is not given; a file of no judged export is judged on its
    folder (``library.rates.at_export_rate``)."""

    skeleton: str | None = None
    fps: float | None = None
    sequence: int = 1
    joint_map: dict | str | Path | None = None
    shared: Mapping[str, SharedRate | None] = field(default_factory=dict)

    def read(self, path: Path):
        ext = path.suffix.lower()
        kw: dict[str, Any] = {"skeleton": self.skeleton, "fps": self.fps} if ext == ".amc" \
            else {"sequence": self.sequence} if ext == ".mat" else {}
        motion = read_motion(path, joint_map=self.joint_map, **kw)
        if self.fps is not None and ext != ".amc":   # the file's own rate is wrong
            motion = motion.replace(fps=self.fps)
        elif self.fps is None and self.shared.get(str(path)) is not None:
            shared = self.shared[str(path)]
            assert shared is not None
            motion = read_at(motion, shared.rate, shared.line(str(path)))
        elif self.fps is None and str(path) in self.shared:   # its export judged: its own
            motion = at_its_rate(motion, str(path))
        elif self.fps is None:   # too few of its export given: judged on its folder
            motion = at_export_rate(motion, path, joint_map=self.joint_map)
        if self.joint_map is not None:   # a map that does not fit this rig: this file's error
            match_rig(motion.skeleton, joint_map=motion.meta["joint_map"])
        return motion


def load_describer_model(model: Any, options: DescribeOptions) -> tuple[Any, Path | None]:
    """``(model, the file it was read from or None)``. Without a bank: ``model`` (loaded, a
    name, a file, a run folder; None: the packaged m2l) of a kind that describes; with one,
    an ``Embedder`` (``library.embedder``) of a model that encodes sentences and motions
    (None: ``bank.default_bank_model``)."""
    named = model is None or isinstance(model, (str, Path))
    if options.bank:
        name = default_bank_model() if model is None else model
        return Embedder.load(name), resolve(name) if named else None
    if not named:
        return model, None
    return load_model(model or "m2l", kind=kinds_with("describes")), resolve(model or "m2l")


class Describer:
    """A loaded model with its options: sentences, timelines and records of motions.
    ``model`` is a model that describes or, with a ``bank``, an ``Embedder`` of a model
    that encodes both sentences and motions."""

    def __init__(self, model: Any, options: DescribeOptions, bank: SentenceBank | None = None,
                 read: ReadOptions | None = None):
        if (bank is None) != (options.bank is None):
            raise MotionlangError("a sentence bank goes with the bank option, both or neither")
        self.model, self.options, self.bank = model, options, bank
        self.reading = read or ReadOptions()

    def detached(self) -> Describer:
        """A copy without the model's weights, to send to a worker that loads them."""
        shell = copy.copy(self)
        if self.bank is None:
            shell.model = None
        else:
            shell.model = copy.copy(self.model)
            shell.model.model = None
        return shell

    def attach(self, loaded: Any) -> None:
        """Put a loaded model into a :meth:`detached` describer."""
        if self.bank is None:
            self.model = loaded
        else:
            self.model.model = loaded

    @property
    def score_key(self) -> str:
        """The name of the score in records: a bank's cosine or a model's log P."""
        return "log_p" if self.bank is None else "cos"

    def sentences(self, motion) -> list[tuple[str, float]]:
        """``[(sentence, score), ...]`` best first, ``width`` of them."""
        o = self.options
        if self.bank is not None:
            return self.bank.nearest(self.model.motion(motion), o.width)
        return family_describer(self.model)(self.model, motion, width=o.width,
                                     length_penalty=o.length_penalty, rank=o.rank,
                                     grounded=not o.raw)

    def timeline(self, motion) -> list[Segment]:
        """The take as segments (``library.timeline``): cut where the grounded analysis sees
        the action change, each segment described on its own; with a bank, raw, or where
        the analysis cannot read the body, its windows' first sentences merged."""
        o = self.options
        if self.bank is None and not o.raw and motion.n_frames > 1:
            try:
                cuts = analyse(motion).timeline()
            except MotionlangError:
                cuts = []
            if cuts:
                end = span(motion)
                segs = []
                for a, b, grounded in self._shown(cuts, motion, "segments"):
                    part = cut(motion, Window(a, min(b, end)))
                    text, score = self.sentences(part)[0]
                    # where the model's sentence does not lead, the segment's own action
                    segs.append(Segment(a, min(b, end), grounded if math.isnan(score) else
                                        text, score))
                return segs
        parts = motion_windows(motion, o.window, o.hop)
        labels = [self.sentences(part)[0] for _, part in self._shown(parts, motion, "windows")]
        return merge_windows([w for w, _ in parts], labels, end=span(motion), merge=o.merge,
                             bridge=o.bridge)

    @staticmethod
    def _shown(items: list, motion, unit: str):
        """``items``, with progress shown on stderr for a take of :data:`LONG_TAKE_S` or
        more (minutes of work with nothing said otherwise)."""
        if motion.duration < LONG_TAKE_S:
            return items
        return progress(items, desc=f"describe {motion.name}", unit=unit)

    def segment_dicts(self, segments: Sequence[Segment]) -> list[dict]:
        return [{"start": round(s.start, 3), "end": round(s.end, 3), "text": s.text,
                 self.score_key: _rounded(s.score)} for s in segments]

    def record(self, path: str | Path) -> dict:
        """The record of one file (module docstring); its failure is its record."""
        out: dict[str, Any] = {"file": str(path)}
        try:
            motion = self.reading.read(Path(path))
            if self.options.segments:
                out["segments"] = self.segment_dicts(self.timeline(motion))
            else:
                out["sentences"] = [{"text": t, self.score_key: _rounded(s)}
                                    for t, s in self.sentences(motion)]
            if self.options.explain:
                out["evidence"] = evidence(motion)
        except MotionlangError as exc:
            out["error"] = " ".join(str(exc).split())
        except Exception as exc:   # noqa: BLE001 - one odd take must not end a long run
            out["error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        return out


def _bank(embedder: Any, options: DescribeOptions,
          show_progress: bool | None) -> SentenceBank | None:
    if not options.bank:
        return None
    return embed_bank(embedder, read_bank(options.bank), show_progress=show_progress)


def describer(model: Any = None, options: DescribeOptions | None = None, *,
              bank: SentenceBank | None = None, read: ReadOptions | None = None,
              show_progress: bool | None = None) -> Describer:
    """A :class:`Describer` of ``model`` (loaded, a name, a file, a run folder; None: the
    packaged default), its bank read and embedded when ``options.bank`` names one (cached
    per model: ``bank.embed_bank``) unless ``bank`` is given."""
    options = options or DescribeOptions()
    loaded = load_describer_model(model, options)[0]
    bank = bank or _bank(loaded, options, show_progress)
    return Describer(loaded, options, bank, read)


def _rounded(score: float) -> float | None:
    """A score for a record: 4 decimals, None for a sentence no model scored (NaN)."""
    return None if math.isnan(score) else round(score, 4)


def evidence(motion) -> list[dict]:
    """``[{"phrase", **finding}, ...]``: each phrase of the grounded sentence with the
    finding behind it (``analysis.Finding.as_dict``); empty where nothing was found."""
    try:
        return [{"phrase": text, **f.as_dict()} for text, f in analyse(motion).explain()]
    except MotionlangError:
        return []


def score_text(label: str, score: float, fmt: str = "8.3f") -> str:
    """``log P =   -3.210``, or ``grounded`` (as wide) for a sentence no model scored."""
    width = len(label) + 3 + int(fmt.split(".")[0])
    return f"{'grounded':>{width}}" if math.isnan(score) else f"{label} = {score:{fmt}}"


def printed(d: Describer, motion, *, as_json: bool = False) -> str:
    """What ``motionlang describe FILE`` prints of one motion: ``1. log P =   -3.210  a
    person walks`` lines (a bank's: ``cos =``), or with segments ``0.0-4.0 s  a person
    walks`` lines; ``as_json``: a JSON list of the sentences (with their rank) or segments;
    with ``explain`` the evidence of the whole take after them (JSON: ``{"sentences" or
    "segments", "evidence"}``)."""
    key = "segments" if d.options.segments else "sentences"
    if d.options.segments:
        segments = d.timeline(motion)
        rows: Any = d.segment_dicts(segments)
        lines = [s.line() for s in segments]
    else:
        hyps, label = d.sentences(motion), "log P" if d.bank is None else "cos"
        rows = [{"rank": i + 1, "text": t, d.score_key: _rounded(s)}
                for i, (t, s) in enumerate(hyps)]
        lines = [f"{i}. {score_text(label, score)}  {text}"
                 for i, (text, score) in enumerate(hyps, 1)]
    if as_json:
        if d.options.explain:
            rows = {key: rows, "evidence": evidence(motion)}
        return json.dumps(rows, indent=1)
    if d.options.explain:
        found = evidence(motion)
        lines.append("evidence:" if found else "evidence: the analysis found nothing it is "
                     "sure of")
        lines += [f"  {e['phrase']}: {e['start']:.2f}-{e['end']:.2f} s, {e['measure']} "
                  f"{e['value']:g} (threshold {e['threshold']:g}), confidence "
                  f"{e['confidence']:.2f}" for e in found]
    return "\n".join(lines)


_WORKER: Describer | None = None


def _start_worker(model_file: Path | None, describer_: Describer, threads: int) -> None:
    """A worker process: its describer, the model loaded from its file once (or sent
    whole when it came loaded)."""
    global _WORKER
    import torch
    torch.set_num_threads(threads)
    if model_file is not None:
        describer_.attach(load_model(model_file))
    _WORKER = describer_


def _worker_record(path: Path) -> dict:
    assert _WORKER is not None, "worker not started"
    return _WORKER.record(path)


@dataclass
class DescribeRun:
    """Files to describe and the describer, checked before anything is written."""

    files: list[Path]
    describer: Describer
    model_file: Path | None = None

    def records(self, *, show_progress: bool | None = None,
                files: Sequence[Path] | None = None) -> Iterator[dict]:
        """One record per file (``files``, default all), in order; ``options.workers``
        processes (at most the CPU count and the files), each loading the model once."""
        d = self.describer
        files = list(self.files if files is None else files)
        workers = max(1, min(d.options.workers, os.cpu_count() or 1, len(files)))
        bar = progress(total=len(files), desc="describe", unit="files",
                       disable=None if show_progress is None else not show_progress)
        with bar:
            if workers == 1:
                for path in files:
                    yield d.record(path)
                    bar.update(1)
                return
            yield from self._in_workers(workers, bar, files)

    def _in_workers(self, workers: int, bar, files: list[Path]) -> Iterator[dict]:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor
        from concurrent.futures.process import BrokenProcessPool

        import torch
        d = self.describer   # a file is cheaper to send than the weights
        shell = d.detached() if self.model_file is not None else d
        threads = max(1, torch.get_num_threads() // workers)
        # spawned, not forked: a fork of a process whose torch runs threads can hang
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(workers, mp_context=ctx, initializer=_start_worker,
                                 initargs=(self.model_file, shell, threads)) as pool:
            try:
                for rec in pool.map(_worker_record, files):
                    yield rec
                    bar.update(1)
            except BrokenProcessPool:
                raise MotionlangError("a describe worker process died (killed, or out of "
                                      "memory); what was done is kept: run the same "
                                      "command again to go on") from None

    def header(self) -> dict:
        """What an interrupted run's partial output must match to be gone on from."""
        return {"motionlang describe": {
            "model": str(self.model_file) if self.model_file is not None else
            str(getattr(self.describer.model, "name", "")),
            "options": {k: v for k, v in vars(self.describer.options).items()
                        if k != "workers"}}}

    def write(self, out: str | Path) -> tuple[int, int]:
        """Write the records as JSON lines to ``out``: as it goes into ``OUT.partial`` (an
        interrupted run, a killed worker, loses nothing; the same command goes on from
        there), then ``out`` at once when every file is done; returns (records, errors)."""
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)   # as every other output's folder
        partial = out.with_name(out.name + ".partial")
        done = _done_before(partial, self.header())
        todo = [p for p in self.files if str(p) not in done]
        with open(partial, "a" if done else "w", encoding="utf-8") as fh:
            if not done:
                fh.write(json.dumps(self.header(), ensure_ascii=False) + "\n")
            for rec in self.records(files=todo):
                done[rec["file"]] = rec
                fh.write(json.dumps(rec, ensure_ascii=False) + "\n")
                fh.flush()
        n = errors = 0
        with atomic_write(out) as fh:
            for p in self.files:
                rec = done[str(p)]
                fh.write(json.dumps(rec, ensure_ascii=False) + "\n")
                n += 1
                errors += "error" in rec
        partial.unlink(missing_ok=True)
        return n, errors


def _done_before(partial: Path, header: dict) -> dict[str, dict]:
    """The records an interrupted run of the same command kept in ``partial`` (by file);
    none where it is missing, of another command or unreadable; a torn last line dropped."""
    try:
        lines = partial.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    try:
        if not lines or json.loads(lines[0]) != json.loads(json.dumps(header)):
            return {}
    except ValueError:
        return {}
    done = {}
    for line in lines[1:]:
        try:
            rec = json.loads(line)
        except ValueError:
            continue
        if isinstance(rec, dict) and isinstance(rec.get("file"), str):
            done[rec["file"]] = rec
    return done


def motion_paths(inputs: Iterable[str | Path]) -> list[Path]:
    """Every motion file of ``inputs``, each once, in the order given: a file as named
    (whatever its extension: the reader says why it cannot read it), a folder's motion files
    (``library.scan.motion_files``: recursive, the extensions the readers know).

    Raises:
        MotionlangError: an input that does not exist, or no motion file at all.
    """
    out: dict[Path, None] = {}
    given = [Path(p) for p in inputs]
    for path in given:
        if not path.exists():
            raise MotionlangError(f"{path}: no such file or folder")
        unlisted: list[tuple[str, str]] = []
        out.update(dict.fromkeys(motion_files(path, unlisted) if path.is_dir() else [path]))
        for folder, why in unlisted:   # never silently: its files are not described
            warnings.warn(f"{(path / folder).as_posix()}/: left out: {why}", UserWarning,
                          stacklevel=2)
    if not out:
        raise MotionlangError(f"{', '.join(map(str, given[:3]))}: no motion files")
    return list(out)


def describe_run(paths: Iterable[str | Path], model: Any = None,
                 options: DescribeOptions | None = None, *, read: ReadOptions | None = None,
                 show_progress: bool | None = None) -> DescribeRun:
    """The run of ``paths`` (files and folders, ``library.files``): the model loaded and
    checked first, then the inputs listed, the bank embedded last."""
    options = options or DescribeOptions()
    loaded, where = load_describer_model(model, options)
    files = motion_paths(paths)
    read = read or ReadOptions()
    if read.fps is None:   # one export, one rate: the files its bodies could not time
        read = replace(read, shared=shared_rates(files, joint_map=read.joint_map,
                                                 show_progress=show_progress))
    bank = _bank(loaded, options, show_progress)
    return DescribeRun(files, Describer(loaded, options, bank, read), where)



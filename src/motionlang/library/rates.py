"""One export, one rate: the BVH files of one folder that share a rig and a declared frame
rate came out of one export, and an exporter that writes a wrong rate writes it into all
of them (MakeHuman's BVH of CMU trials declare 25 Hz for 120 Hz frames).

The body can time a take only where it steps or flies (``analysis.rate``); a punch, a climb
or a bow says nothing of its rate. Where such files sit in an export whose other files
the body did time, they are read at the rate those showed:

- files are grouped by folder, the rig's joint names and the declared rate (from the
  header alone, ``formats.bvh_read.bvh_header``), for declared rates of at most
  ``analysis.rate.SUSPECT_BELOW`` Hz;
- a group is read at a shared rate only where at least :data:`MIN_TIMED` of its files name
  rates (``RateHint``), :data:`AGREE` of them the same one (the rate their flights fall at g
  at, where there are flights; else the rate most name first), and none of its files
  confirms the declared rate (it steps, or its flights fall at g, at that rate): one such
  file settles the group, and the rest of it is not read twice;
- every file of the group is then read at that rate, the timed ones too, so that an export's
  takes keep one clock.

A single file (``describe FILE``, ``check``, ``ml.describe(path)``) that its body cannot time
is judged so on a sample of its folder's files of its rig and rate (:func:`at_export_rate`).
A file given with ``--source-fps`` is read at that rate, whatever its folder.
"""
from __future__ import annotations

import math
import random
from collections import Counter, defaultdict
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.analysis.rate import (
    CLI_ADVICE,
    RATES,
    SUSPECT_BELOW,
    RateHint,
    read_at,
    verdict_of,
)
from motionlang.errors import MotionlangError
from motionlang.formats import read_motion
from motionlang.formats.bvh_read import bvh_header
from motionlang.kinematics.motion import Motion
from motionlang.utils.progress import progress

#: files of one export whose bodies must name a rate before the others follow
MIN_TIMED = 2
#: share of those files that must name the export's rate among theirs
AGREE = 0.75
#: a single file's folder mates whose headers are read (a sample, in a fixed shuffled
#: order), and of those of its rig and declared rate, the files read, where its own body
#: cannot time it
SIBLINGS = 64
SIBLINGS_READ = 12


@dataclass(frozen=True)
class SharedRate:
    """The rate a file is read at because of its export: ``rate`` (Hz) where its header says
    ``declared``; ``timed``: the files of its folder and rig whose bodies allow it (their
    steps or flights name it among their rates)."""

    rate: float
    declared: float
    timed: int

    def line(self, where: str, *, advice: str | None = CLI_ADVICE) -> str:
        return (f"{where}: its header says {self.declared:g} Hz; read at {self.rate:g} Hz, "
                f"the rate the steps or flights of {self.timed} files of its folder and rig "
                "showed" + (f" ({advice})" if advice else ""))


def _export_rate(hints: Sequence[RateHint]) -> float | None:
    """The rate the hints of one export give: where flights were fitted, the capture rate
    nearest their median fall (gravity gives the rate itself), else the rate most hints
    name first; None unless at least :data:`AGREE` of the hints name it among theirs."""
    falls = [h.fall_rate for h in hints if h.fall_rate is not None]
    named = sorted({r for h in hints for r in h.rates})
    if falls:
        middle = float(np.median(falls))
        rate = min(named, key=lambda r: abs(math.log(r / middle)))
    else:
        firsts = Counter(h.rate for h in hints)
        rate = min(named, key=lambda r: (-firsts[r], sum(
            h.rates.index(r) if r in h.rates else len(RATES) for h in hints), r))
    support = sum(rate in h.rates for h in hints) / len(hints)
    return rate if support >= AGREE else None


def _hints_of(members: Sequence[Path], joint_map, tick) -> list[RateHint] | None:
    """The rate hints of ``members`` (one export), read in an order that mixes the folder's
    kinds of take (names sort walks with walks); None as soon as one confirms the declared
    rate (the export's rate is right: the rest is not read). ``tick(n)``: n files done."""
    order = list(members)
    random.Random(len(order)).shuffle(order)
    hints: list[RateHint] = []
    for i, path in enumerate(order):
        tick(1)
        try:
            verdict = verdict_of(read_motion(path, joint_map=joint_map))
        except MotionlangError:
            continue
        if verdict.own:
            tick(len(order) - i - 1)
            return None
        if verdict.hint is not None:
            hints.append(verdict.hint)
    return hints


def _shared(hints: list[RateHint] | None, declared: float) -> SharedRate | None:
    rate = _export_rate(hints) if hints is not None and len(hints) >= MIN_TIMED else None
    if rate is None or hints is None:
        return None
    return SharedRate(rate, declared, sum(rate in h.rates for h in hints))


def shared_rates(files: Sequence[Path], *, joint_map: dict | str | Path | None = None,
                 only: Collection[Path] | None = None,
                 show_progress: bool | None = None) -> dict[str, SharedRate | None]:
    """``{str(path): SharedRate or None}`` for the files of ``files`` judged with an export
    of theirs (module docstring; None: as each file's own body says), read with
    ``joint_map`` (a rig no built-in map fits); files of exports too small to judge among
    ``files`` are not keys (:func:`at_export_rate` judges each on its folder); files that do
    not read are left to their reader to name. ``only``: judge only the exports that hold
    one of these files (an index's files of this run, its shard: the exports that hold
    them are judged whole)."""
    groups: dict[tuple, list[Path]] = defaultdict(list)
    for path in files:
        if path.suffix.lower() != ".bvh":
            continue
        try:
            joints, fps = bvh_header(path)
        except MotionlangError:
            continue
        if 0 < fps <= SUSPECT_BELOW:
            groups[(path.parent, joints, fps)].append(path)
    wanted = None if only is None else set(only)
    todo = [(key, members) for key, members in groups.items() if len(members) > MIN_TIMED
            and (wanted is None or not wanted.isdisjoint(members))]
    out: dict[str, SharedRate | None] = {}
    with progress(total=sum(len(m) for _, m in todo), desc="frame rates", unit="files",
                  disable=None if show_progress is None else not show_progress) as bar:
        for (_, _, declared), members in todo:
            shared = _shared(_hints_of(members, joint_map, bar.update), declared)
            out.update((str(p), shared) for p in members)
    return out


def export_rate(path: Path, *, joint_map: dict | str | Path | None = None
                ) -> SharedRate | None:
    """The rate of the export one BVH file ``path`` belongs to, where its header declares
    30 Hz or less: a sample of its folder's other files (:data:`SIBLINGS` headers read, of
    those of its rig and declared rate :data:`SIBLINGS_READ` files) judged as
    :func:`shared_rates` judges a folder; None where they do not settle one."""
    if path.suffix.lower() != ".bvh":
        return None
    try:
        head = bvh_header(path)
        others = sorted(p for p in path.parent.iterdir()
                        if p.suffix.lower() == ".bvh" and p.name != path.name)
    except (MotionlangError, OSError):
        return None
    if not 0 < head[1] <= SUSPECT_BELOW:
        return None
    random.Random(len(others)).shuffle(others)
    same = []
    for other in others[:SIBLINGS]:
        try:
            if bvh_header(other) == head:
                same.append(other)
        except MotionlangError:
            continue
    return _shared(_hints_of(same[:SIBLINGS_READ], joint_map, lambda n: None), head[1])


def at_export_rate(motion: Motion, path: str | Path, *,
                   joint_map: dict | str | Path | None = None,
                   advice: str | None = CLI_ADVICE) -> Motion:
    """``motion``, read from the file ``path``, at the rate of its export
    (:func:`export_rate`) where its body cannot tell or allows it, else at the rate its
    body says (``analysis.rate.at_its_rate``), with one warning that says so (and
    ``advice``); as it is where its body confirms its rate or no body can be read (a rig
    no map fits, one frame)."""
    verdict = verdict_of(motion)
    if verdict.own or not verdict.read:   # its rate is right, or there is no body to time
        return motion
    shared = export_rate(Path(path), joint_map=joint_map)
    hint = verdict.hint
    if hint is not None and (shared is None or shared.rate not in hint.rates):
        return read_at(motion, hint.rate, hint.line(str(path), read=True, advice=advice))
    if shared is None:
        return motion
    # the export's rate, where the file's own steps or flights allow it: one clock for all
    return read_at(motion, shared.rate, shared.line(str(path), advice=advice))

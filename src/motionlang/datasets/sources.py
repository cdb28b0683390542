"""Data sources as objects: what a ``--data`` value names, how it is read, under which licence.

A source is written ``[PREFIX:]ROOT[@WEIGHT]``: a prefix names a kind of dataset
(``bandai:DIR``, ``humanml3d:DIR``, ``kitml-h3d:DIR``); a bare folder is a KIT-ML-format
release (or a procedural corpus, written in that format) when it holds ``*_mmm.xml`` files,
else a custom folder of motion files with a captions file. ``@WEIGHT`` sets the source's share
of a training epoch when several are mixed (``datasets.mixing``).

Each kind is one :class:`SourceKind` in :data:`KINDS` (its prefix, its loader as
``"module:function"``, its licence, a line for help texts); adding a dataset is a loader that
returns :class:`Record` objects and one :func:`register` call. The licence of whatever is
trained on some sources is decided here, once (:func:`licence_of`, :func:`non_commercial`,
:func:`licence_text`), from the sources' own licences.

Torch-free; loaders are imported only when a source is loaded.
"""
from __future__ import annotations

import importlib
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from motionlang.datasets.kitml import find_kitml_root
from motionlang.errors import DatasetError, MotionlangError

if TYPE_CHECKING:
    from motionlang.kinematics import Motion

#: the licence of a source whose terms are its own (a user's folder, a converted release):
#: nothing that motionlang adds to them
OWN_TERMS = "the data's own terms"
#: licences that make whatever is trained on the data non-commercial, with their text
NON_COMMERCIAL = {"CC BY-NC 4.0": "https://creativecommons.org/licenses/by-nc/4.0/"}
#: the file a training run writes its licence note into (``licence_text``)
LICENCE_FILE = "LICENSE.txt"


@runtime_checkable
class Record(Protocol):
    """One motion of a dataset and its descriptions, as every loader returns it
    (``KitMLRecord``, ``CustomRecord``, ``H3DRecord``, ``BandaiRecord``).

    Records may also carry ``split`` (``"train"``/``"val"``/``"test"``: the dataset's own
    split, used where every record names one) and ``path`` or ``mmm_path`` (the motion file,
    part of cache keys).
    """

    @property
    def id(self) -> str:
        """Unique within the dataset (split files list ids)."""
        ...

    @property
    def annotations(self) -> list[str]:
        """English descriptions, possibly none."""
        ...

    @property
    def has_annotations(self) -> bool: ...

    @property
    def meta(self) -> dict:
        """Whatever the dataset says about the motion (labels, primitives, captions' lines)."""
        ...

    def load_motion(self) -> Motion:
        """Read the motion (files are read only here, not when the dataset is listed)."""
        ...


@dataclass(frozen=True)
class SourceKind:
    """One kind of dataset.

    Attributes:
        name: e.g. ``"bandai"``. prefix: ``"bandai:"``, or ``""`` for a bare folder.
        loader: ``"module:function"`` called as ``function(root, **options, max_seconds=...,
            joint_map=...)``, the last two only where named in ``reads``; returns records.
        licence: the data's licence (a key of :data:`NON_COMMERCIAL` restricts the use of
            anything trained on it), else :data:`OWN_TERMS`.
        description: one line for ``--data`` help texts.
        title: the data named in a licence note (``licence_text``); notice: its
            attribution line there.
        reads: which of ``max_seconds`` and ``joint_map`` the loader takes.
        options: fixed keyword arguments of the loader, as ``(name, value)`` pairs.
    """

    name: str
    prefix: str
    loader: str
    licence: str
    description: str
    title: str = ""
    notice: str = ""
    reads: tuple[str, ...] = ()
    options: tuple[tuple[str, Any], ...] = ()


#: every kind by name; the bare-folder kinds have no prefix (:func:`folder_kind` picks one)
KINDS: dict[str, SourceKind] = {}


def register(kind: SourceKind) -> SourceKind:
    """Add a kind of dataset (its name and prefix must be new)."""
    if kind.name in KINDS:
        raise MotionlangError(f"data source kind {kind.name!r} is already registered")
    if kind.prefix and (not kind.prefix.endswith(":") or kind.prefix in prefixes()):
        raise MotionlangError(f"data source prefix {kind.prefix!r}: must end with ':' and be "
                              "new")
    KINDS[kind.name] = kind
    return kind


def prefixes() -> dict[str, SourceKind]:
    """``{"bandai:": kind, ...}``: the prefixed kinds."""
    return {k.prefix: k for k in KINDS.values() if k.prefix}


register(SourceKind(
    "kitml", "", "motionlang.datasets.kitml:load_kitml", OWN_TERMS,
    "a KIT-ML-format release or procedural corpus (a folder of *_mmm.xml files)",
    reads=("max_seconds",)))
register(SourceKind(
    "custom", "", "motionlang.datasets.custom:load_custom", OWN_TERMS,
    "any other folder: motion files (BVH, ASF/AMC, MMM) and captions.csv or captions.jsonl",
    reads=("joint_map",)))
register(SourceKind(
    "bandai", "bandai:", "motionlang.datasets.bandai:load_bandai_text", "CC BY-NC 4.0",
    "the Bandai Namco Research Motion Datasets (a clone, its .tar.xz archives or one "
    "dataset folder), sentences written from their labels; CC BY-NC 4.0: what is trained "
    "on them is non-commercial",
    title="the Bandai Namco Research Motion Datasets",
    notice="Bandai Namco Research Motion Dataset, CC BY-NC 4.0: non-commercial use only, "
           "with attribution to Bandai Namco Research Inc.",
    reads=("max_seconds",)))
register(SourceKind(
    "library", "library:", "motionlang.datasets.library:load_library", OWN_TERMS,
    "a motion library without captions: the grounded analysis' sentence of each take, its "
    "folder's captions file where there is one, and the words of its path",
    reads=("max_seconds",)))
register(SourceKind(
    "analysis", "analysis:", "motionlang.datasets.library:load_library", OWN_TERMS,
    "a motion library captioned by the grounded analysis alone (no names, no captions file)",
    reads=("max_seconds",), options=(("names", False),)))
register(SourceKind(
    "humanml3d", "humanml3d:", "motionlang.datasets.humanml3d:load_h3d", OWN_TERMS,
    "a HumanML3D-layout folder, 22 SMPL joints at 20 fps (its own split files)",
    reads=("max_seconds",), options=(("body", "smpl"),)))
register(SourceKind(
    "kitml-h3d", "kitml-h3d:", "motionlang.datasets.humanml3d:load_h3d", OWN_TERMS,
    "a HumanML3D-layout folder of the KIT-ML body, 21 joints at 12.5 fps (its own split "
    "files)",
    reads=("max_seconds",), options=(("body", "kit"),)))


def folder_kind(root: str | Path) -> str:
    """The kind of a bare folder: ``"kitml"`` where it holds ``*_mmm.xml`` files (up to two
    levels down, ``kitml.find_kitml_root``), else ``"custom"`` (a missing folder too: its
    loader says so)."""
    try:
        find_kitml_root(root)
    except DatasetError:
        return "custom"
    return "kitml"


def _weight_text(w: float) -> str:
    text = repr(float(w))   # the shortest text that reads back as the same float
    return text[:-2] if text.endswith(".0") else text


@dataclass(frozen=True)
class DataSource:
    """One dataset to read: its kind (a key of :data:`KINDS`), its root (a folder, as the
    loader takes it), its sampling weight (None: not given) and its licence (default: the
    kind's; give one to state a custom folder's terms).

    ``str(source)`` is the ``--data`` text (``bandai:DIR@0.5``); :func:`parse_source` reads
    it back to an equal source.

    Raises:
        MotionlangError: an unknown kind, an empty root, a weight that is not positive and
            finite.
    """

    kind: str
    root: str
    weight: float | None = None
    licence: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise MotionlangError(f"unknown data source kind {self.kind!r} (known: "
                                  f"{', '.join(KINDS)})")
        object.__setattr__(self, "root", str(self.root))
        if not self.root.strip():
            raise MotionlangError(f"{self.kind} data source: no folder given")
        if self.weight is not None:
            w = float(self.weight)
            if not (math.isfinite(w) and w > 0):
                raise MotionlangError(f"{self.path}@{self.weight}: the weight after '@' must "
                                      "be a positive number")
            object.__setattr__(self, "weight", w)
        if not self.licence:
            object.__setattr__(self, "licence", KINDS[self.kind].licence)

    @property
    def path(self) -> str:
        """The text without the weight (``bandai:DIR``)."""
        return KINDS[self.kind].prefix + self.root

    @property
    def non_commercial(self) -> bool:
        return self.licence in NON_COMMERCIAL

    def __str__(self) -> str:
        return self.path if self.weight is None else f"{self.path}@{_weight_text(self.weight)}"


def parse_source(text: str | Path | DataSource, kind: str | None = None) -> DataSource:
    """``[PREFIX:]ROOT[@WEIGHT]`` -> a :class:`DataSource`.

    The weight is a positive number after the last ``@``; when what follows the last ``@`` is
    not a number the text is a root whole (``/data/me@home``). A prefix is one of
    :func:`prefixes`; any other text is a bare folder (``C:\\data``, ``s3://x`` too), whose
    kind :func:`folder_kind` decides, or ``kind`` where given. With ``kind``, a source of
    another prefixed kind is refused (a command that reads one kind only).

    Raises:
        MotionlangError: an empty root (``"bandai:"``, ``"@1"``), a weight that is not
            positive and finite, an unknown ``kind``, another kind than ``kind``.
    """
    if kind is not None and kind not in KINDS:
        raise MotionlangError(f"unknown data source kind {kind!r} (known: {', '.join(KINDS)})")
    if isinstance(text, DataSource):
        if kind is not None and text.kind != kind:
            raise MotionlangError(f"{text}: a {text.kind} source; expected a {kind} one")
        return text
    text = str(text)
    head, at, tail = text.rpartition("@")
    weight = None
    if at:
        try:
            weight = float(tail)
        except ValueError:
            head = text
        else:
            if not (math.isfinite(weight) and weight > 0):
                raise MotionlangError(f"{text}: the weight after '@' must be a positive number")
    else:
        head = text
    found = next((k for p, k in prefixes().items() if head.startswith(p)), None)
    root = head[len(found.prefix):] if found else head
    if not root.strip():
        what = (f"no folder after {found.prefix!r}" if found else
                "no dataset before the weight" if weight is not None else "no dataset named")
        raise MotionlangError(f"{text!r}: {what}")
    if found is None:
        return DataSource(kind or folder_kind(root), root, weight)
    if kind is not None and found.name != kind:
        want = KINDS[kind].prefix or "a folder"
        raise MotionlangError(f"{text}: a {found.name} source; expected {want}DIR")
    return DataSource(found.name, root, weight)


def load(source: str | Path | DataSource, max_seconds: float | None = 30.0,
         joint_map: str | Path | dict | None = None) -> list[Record]:
    """The records of ``source`` (parsed first if text), by its kind's loader.

    max_seconds: leave out longer motions (where the loader reads it: not a custom folder).
    joint_map: how a custom folder's rig maps onto the 21-joint body (``load_custom``).

    Raises:
        DatasetError: whatever the loader refuses (missing folder, malformed files).
    """
    source = parse_source(source)
    kind = KINDS[source.kind]
    module, _, name = kind.loader.partition(":")
    loader = getattr(importlib.import_module(module), name)
    given = {"max_seconds": max_seconds, "joint_map": joint_map}
    return loader(source.root, **dict(kind.options),
                  **{k: v for k, v in given.items() if k in kind.reads})


def _sources(sources: Iterable[str | Path | DataSource] | str | Path | DataSource
             ) -> list[DataSource]:
    if isinstance(sources, (str, Path, DataSource)):
        sources = [sources]
    return [parse_source(s) for s in sources]


def licence_of(sources: Iterable[str | Path | DataSource] | str | Path | DataSource) -> str:
    """The licence of whatever is trained on ``sources``: their licences other than
    :data:`OWN_TERMS`, each once, in order, joined by ``"; "``; :data:`OWN_TERMS` when none
    states one."""
    stated = dict.fromkeys(s.licence for s in _sources(sources) if s.licence != OWN_TERMS)
    return "; ".join(stated) or OWN_TERMS


def non_commercial(sources: Iterable[str | Path | DataSource] | str | Path | DataSource
                   ) -> bool:
    """True when any source's licence is non-commercial (:data:`NON_COMMERCIAL`): whatever is
    trained on them, and the figures made with it, are then for non-commercial use only."""
    return any(s.non_commercial for s in _sources(sources))


def licence_text(sources: Iterable[str | Path | DataSource] | str | Path | DataSource,
                 what: str) -> str | None:
    """The :data:`LICENCE_FILE` note of ``what`` (e.g. ``"M2L"``) trained on ``sources``, or
    None when no source restricts its use (one paragraph per restricting kind and licence)."""
    restricting = {(s.kind, s.licence): s for s in _sources(sources) if s.non_commercial}
    notes = []
    for s in restricting.values():
        kind = KINDS[s.kind]
        data = kind.title or f"{kind.name} data"
        note = (f"Trained on {data} ({s.licence}): the {what} and the figures made with it "
                f"are for non-commercial use only.\n\n")
        if kind.notice:
            note += f"Data: {kind.notice}\n"
        notes.append(note + f"Licence text: {NON_COMMERCIAL[s.licence]}\n")
    return "\n".join(notes) or None


def data_help(weights: bool = True) -> str:
    """The help text of ``--data``, from :data:`KINDS`."""
    bare = [k for k in KINDS.values() if not k.prefix]
    parts = ["DIR: " + "; else ".join(k.description for k in bare)]
    parts += [f"{k.prefix}DIR: {k.description}" for k in KINDS.values() if k.prefix]
    text = ". ".join(parts) + "."
    if weights:
        text += (" Append @WEIGHT (a positive number) to set a dataset's share of a training "
                 "epoch when several are given.")
    return text


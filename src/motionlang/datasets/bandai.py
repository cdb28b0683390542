"""The Bandai Namco Research Motion Datasets 1 and 2: real BVH takes with action and style
labels (CC BY-NC 4.0: anything trained on them is for non-commercial use only).

Layout (the public repository's ``dataset/`` folder, and each release archive)::

    Bandai-Namco-Research-Motiondataset-N/
        data/dataset-N_<content>_<style>_<take>.bvh   (30 fps, one 22-joint rig, cm)
        data/dataset-N_<content>_<style>_<take>.json  {"content": i, "style": j}
        cfg/content_label.txt, cfg/style_label.txt     one "dataset-N_<label>" a line

:func:`bandai_folders` finds the dataset folders under a clone of the repository, a folder
of the two ``.tar.xz`` archives (extracted once into the cache, outside the source folder)
or one dataset folder; :func:`load_bandai` lists the takes with their labels and split;
:func:`load_bandai_text` adds English sentences for the labels (``bandai_text``) and,
optionally, mirrored copies: records as the other datasets' (``id``, ``annotations``,
``load_motion``), which ``sources.load("bandai:PATH")`` returns.
Splits are deterministic: in dataset 2, takes numbered 0 mod 5 are test, 4 mod 5
validation, the rest training; dataset 1 (one take per label) is all training.
"""
from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

from motionlang.datasets.bandai_text import describe, mirror_sentence
from motionlang.datasets.cache import cache_dir
from motionlang.datasets.download import safe_extract_tar, sha256_file
from motionlang.datasets.sources import KINDS
from motionlang.errors import DatasetError
from motionlang.formats import read_motion  # lower layer, loaded lazily
from motionlang.kinematics.from_positions import mirror_motion
from motionlang.utils.paths import check_inside

LICENSE = KINDS["bandai"].notice   # the attribution line, kept with the source registry
ARCHIVE = re.compile(r"^(Bandai-Namco-Research-Motiondataset-\d+)\.tar(\.xz|\.gz|\.bz2)?$")
TAKE = re.compile(r"^dataset-(\d+)_(.+)_(\d+)$")


@dataclass
class BandaiRecord:
    """One take.

    Attributes:
        id: the file stem, e.g. ``"dataset-2_walk_normal_003"``.
        path: the BVH file.
        dataset: 1 or 2.
        content: action label, e.g. ``"walk-turn-left"``.
        style: style label, e.g. ``"elderly"``.
        take: take number (1-based, per content x style).
        split: ``"train"``, ``"val"`` or ``"test"``.
        sentences: English for the labels (``bandai_text.Sentence``; see
            :func:`load_bandai_text`), none from :func:`load_bandai`.
        mirrored: the take mirrored left/right (id ``"M" + id``; content label mirrored).
    """
    id: str
    path: Path
    dataset: int
    content: str
    style: str
    take: int
    split: str
    meta: dict = field(default_factory=dict)
    sentences: list = field(default_factory=list)
    mirrored: bool = False

    @property
    def annotations(self) -> list[str]:
        """The sentences' text, as ``KitMLRecord.annotations``."""
        return [s.text for s in self.sentences]

    @property
    def has_annotations(self) -> bool:
        return bool(self.sentences)

    @property
    def labels(self) -> dict[str, str]:
        return {"content": self.content, "style": self.style}

    def load_motion(self):
        """Read the take (``formats.read_motion``; mirrored by
        ``kinematics.from_positions.mirror_motion`` if ``mirrored``); labels in ``meta``."""
        motion = read_motion(self.path)
        if self.mirrored:
            motion = mirror_motion(motion)
        motion.meta.update(dataset="bandai", content=self.content, style=self.style,
                           take=self.take, licence=LICENSE)
        return motion


def split_of(dataset: int, take: int) -> str:
    """The deterministic split of a take (see the module docstring)."""
    if dataset != 2:
        return "train"
    return {0: "test", 4: "val"}.get(take % 5, "train")


def _extract(archive: Path) -> Path:
    """The archive's dataset folder, extracted into ``cache_dir()/bandai`` on first use.

    The extraction is stamped with the archive's size and SHA-256, not its time: a copy of
    the same archive (a fresh checkout, ``cp`` without ``-p``) reuses it, so the extracted
    files keep their times and the feature caches keyed on them still hit (re-extracting
    would make every later training run prepare its features again, a long wait)."""
    dest = cache_dir() / "bandai" / ARCHIVE.match(archive.name).group(1)
    stamp = {"size": archive.stat().st_size, "sha256": sha256_file(archive)}
    marker = dest / ".source.json"
    if marker.is_file():
        try:
            if json.loads(marker.read_text()) == stamp:
                return dest / dest.name
        except ValueError:
            pass
    if dest.exists():  # another archive of that name, or an interrupted run: start again
        import shutil
        shutil.rmtree(dest)
    safe_extract_tar(archive, dest, keep=lambda n: "/data/" in n or "/cfg/" in n
                     or n.endswith(("LICENSE", "README.md")))
    marker.write_text(json.dumps(stamp))
    return dest / dest.name


def bandai_folders(source: str | Path) -> list[Path]:
    """Dataset folders (each holding ``data/`` and ``cfg/``) under ``source``.

    Raises:
        DatasetError: ``source`` holds neither the folders nor the archives.
    """
    source = Path(source)
    if not source.is_dir():
        raise DatasetError(f"{source}: Bandai Namco folder not found")
    if (source / "data").is_dir() and (source / "cfg").is_dir():
        return [source]
    found = sorted(p.parent.parent for p in source.glob("**/data/dataset-*_*.bvh"))
    folders = sorted({p for p in found if (p / "cfg").is_dir()})
    if not folders:
        folders = [_extract(p) for p in sorted(source.iterdir()) if ARCHIVE.match(p.name)]
    if not folders:
        raise DatasetError(f"{source}: no Bandai Namco dataset folders (data/, cfg/) or "
                           "archives (Bandai-Namco-Research-Motiondataset-N.tar.xz)")
    return folders


def _labels(folder: Path, name: str) -> list[str]:
    path = folder / "cfg" / name
    try:
        lines = path.read_text(encoding="utf-8").split()
    except OSError as exc:
        raise DatasetError(f"{path}: cannot read labels: {exc.strerror or exc}") from None
    return [re.sub(r"^dataset-\d+_", "", x) for x in lines]


def load_bandai(source: str | Path, split: str | None = None) -> list[BandaiRecord]:
    """Every take under ``source`` (see :func:`bandai_folders`), sorted by id; only one
    split's takes when ``split`` is given.

    Raises:
        DatasetError: missing folders or label files, or a take whose labels disagree with
            its file name.
    """
    if split not in (None, "train", "val", "test"):
        raise DatasetError(f"unknown split {split!r}; use 'train', 'val' or 'test'")
    records = []
    for folder in bandai_folders(source):
        contents, styles = _labels(folder, "content_label.txt"), _labels(folder, "style_label.txt")
        takes = sorted((folder / "data").glob("*.bvh"))
        check_inside(takes, folder)
        for path in takes:
            m = TAKE.match(path.stem)
            if not m:
                continue
            dataset, take = int(m.group(1)), int(m.group(3))
            content, style = _split_name(m.group(2), contents, styles, path)
            rec = BandaiRecord(path.stem, path, dataset, content, style, take,
                               split_of(dataset, take))
            if split is None or rec.split == split:
                records.append(rec)
    return sorted(records, key=lambda r: r.id)


def bvh_seconds(path: Path) -> float:
    """A BVH file's duration from its header (``Frames:`` x ``Frame Time:``), unparsed."""
    head = {}
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            key, _, value = line.partition(":")
            if key.strip() in ("Frames", "Frame Time"):
                head[key.strip()] = float(value)
                if len(head) == 2:
                    return head["Frames"] * head["Frame Time"]
    raise DatasetError(f"{path}: no 'Frames:' / 'Frame Time:' lines (not a BVH file)")


def load_bandai_text(source: str | Path, split: str | None = None, *, per_take: int = 3,
                     seed: int = 0, mirror: bool = False, max_seconds: float | None = None
                     ) -> list[BandaiRecord]:
    """:func:`load_bandai`'s takes with ``per_take`` English sentences each
    (``bandai_text.describe``, seeded by ``seed`` and the take's id, so the same on every
    run); with ``mirror``, each take also mirrored (left/right swapped in motion, text and
    label; same split). ``max_seconds``: leave out longer takes (header read only).
    """
    import zlib

    out = []
    for rec in load_bandai(source, split):
        if max_seconds is not None and bvh_seconds(rec.path) > max_seconds:
            continue
        rec.sentences = describe(rec.content, rec.style, per_take,
                                 seed=zlib.crc32(f"{seed}/{rec.id}".encode()))
        out.append(rec)
        if mirror:
            m = [mirror_sentence(s) for s in rec.sentences]
            out.append(replace(rec, id=f"M{rec.id}", content=m[0].content, sentences=m,
                               mirrored=True, meta=dict(rec.meta)))
    return out


def _split_name(middle: str, contents: list[str], styles: list[str], path: Path
                ) -> tuple[str, str]:
    """``"walk-turn-left_elderly"`` -> (content, style), checked against the label lists
    (labels contain '-' but never '_')."""
    content, _, style = middle.rpartition("_")
    if content not in contents or style not in styles:
        raise DatasetError(f"{path}: content {content!r} / style {style!r} not in the labels "
                           f"of {path.parent.parent / 'cfg'}")
    return content, style

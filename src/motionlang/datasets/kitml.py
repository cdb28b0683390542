"""The KIT Motion-Language dataset (Plappert, Mandery & Asfour 2016): download and loading.

The release is one zip published by KIT. Per motion id ``NNNNN`` it holds
``NNNNN_mmm.xml`` (MMM motion, 100 Hz), ``NNNNN_annotations.json`` (a JSON list of English
sentences, possibly empty), ``NNNNN_meta.json`` and ``NNNNN_raw.c3d`` (raw markers, not used
here). Release 2016-10-10: 3,911 motions, 6,278 annotations; Plappert et al. 2018 keep the
motions shorter than 30 s (2,846 of them).

Download address: KIT's dataset page (https://motion-annotation.humanoids.kit.edu/dataset/)
lists the releases as 2016-06-14, 2016-09-20, 2016-10-10 and 2017-06-22, served as
``/downloads/<n>/``. ``/downloads/4/`` is the 2017-06-22 zip (cited as such by several
projects); ``/downloads/3/`` is therefore the 2016-10-10 zip, the default here. KIT
publishes no checksum for either, so none is built in: pass ``sha256=`` once you have one.
"""
from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import urlparse

from motionlang.datasets.download import download_file, safe_extract
from motionlang.errors import DatasetError
from motionlang.formats.mmm import read_mmm  # formats are a lower layer, loaded lazily
from motionlang.utils.paths import check_inside
from motionlang.utils.progress import progress

if TYPE_CHECKING:
    from motionlang.kinematics import Motion

KITML_URL = "https://motion-annotation.humanoids.kit.edu/downloads/3/"   # 2016-10-10.zip
KITML_2017_URL = "https://motion-annotation.humanoids.kit.edu/downloads/4/"  # 2017-06-22.zip
KITML_ARCHIVE = "2016-10-10.zip"
KITML_FPS = 100.0
EXTRACTED = "kitml"  # folder inside ``dest`` that download_kitml extracts into

_ID = re.compile(r"^(\d+)_mmm\.xml$")
_FRAME = re.compile(rb"<MotionFrame[\s>]")
_STEP = re.compile(rb"<Timestep>\s*([^<\s]+)\s*</Timestep>")


@dataclass
class KitMLRecord:
    """One KIT-ML motion and its descriptions.

    Attributes:
        id: the five-digit id, e.g. ``"00001"``.
        mmm_path: the ``NNNNN_mmm.xml`` file.
        annotations: English sentences, possibly none (such records are kept, see
            ``has_annotations``).
        meta: the parsed ``NNNNN_meta.json`` (``{}`` if there is none).
        n_frames: number of frames of the MMM file (100 Hz).
    """
    id: str
    mmm_path: Path
    annotations: list[str]
    meta: dict = field(default_factory=dict)
    n_frames: int = 0
    fps: float = KITML_FPS

    @property
    def duration_s(self) -> float:
        return self.n_frames / self.fps

    @property
    def has_annotations(self) -> bool:
        return bool(self.annotations)

    def load_motion(self) -> Motion:
        """Read the MMM file (``motionlang.formats.mmm.read_mmm``)."""
        return read_mmm(self.mmm_path)


def count_mmm_frames(path: str | Path, fps: float = KITML_FPS, window: int = 1 << 16) -> int:
    """Number of frames of an MMM file, read cheaply.

    The full release is ~3.6 GB of MMM XML, so a large file is not parsed: the first and
    last ``<Timestep>`` are read from its first and last ``window`` bytes and the count is
    ``round((t_last - t_first) * fps) + 1``. Small files, or files whose time stamps cannot
    be found there, are counted exactly (``<MotionFrame>`` elements in the raw bytes).
    """
    path = Path(path)
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            if size > 2 * window:
                head = fh.read(window)
                fh.seek(size - window)
                tail = fh.read(window)
                first, last = _STEP.search(head), _STEP.findall(tail)
                if first and last:
                    try:
                        span = float(last[-1]) - float(first.group(1))
                    except ValueError:
                        span = -1.0
                    if span >= 0:
                        return int(round(span * fps)) + 1
                fh.seek(0)
            return len(_FRAME.findall(fh.read()))
    except OSError as exc:
        raise DatasetError(f"{path}: cannot read ({exc.strerror})") from None


def find_kitml_root(root: str | Path) -> Path:
    """The folder holding the ``*_mmm.xml`` files: ``root`` or a folder up to two levels
    below it (archives may wrap the files in a top-level folder)."""
    root = Path(root)
    if not root.is_dir():
        raise DatasetError(f"{root}: KIT-ML folder not found")
    for pattern in ("*_mmm.xml", "*/*_mmm.xml", "*/*/*_mmm.xml"):
        hit = next(iter(sorted(root.glob(pattern))), None)
        if hit is not None:
            return hit.parent
    raise DatasetError(f"{root}: no KIT-ML motions (*_mmm.xml) found")


def _read_json(path: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DatasetError(f"{path}: missing (each KIT-ML id needs _mmm.xml, "
                           "_annotations.json and _meta.json)") from None
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{path}:{exc.lineno}: invalid JSON ({exc.msg})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{path}: cannot read ({exc})") from None


def read_record(folder: Path, mid: str) -> KitMLRecord:
    """Parse the three files of one id (no frame filter)."""
    ann_path = folder / f"{mid}_annotations.json"
    ann = _read_json(ann_path)
    if not isinstance(ann, list) or not all(isinstance(a, str) for a in ann):
        raise DatasetError(f"{ann_path}: expected a JSON list of strings")
    meta = _read_json(folder / f"{mid}_meta.json")
    if not isinstance(meta, dict):
        raise DatasetError(f"{folder / f'{mid}_meta.json'}: expected a JSON object")
    mmm = folder / f"{mid}_mmm.xml"
    return KitMLRecord(mid, mmm, [a.strip() for a in ann if a.strip()], meta,
                       count_mmm_frames(mmm, KITML_FPS))


def load_kitml(root: str | Path, max_seconds: float | None = 30.0, *,
               require_annotations: bool = False) -> list[KitMLRecord]:
    """All KIT-ML records under ``root``, sorted by id.

    Args:
        root: the extracted release (or a folder above it, see ``find_kitml_root``).
        max_seconds: drop motions of this duration or longer (frames / 100 Hz);
            ``None`` keeps everything.
        require_annotations: raise on a kept motion whose annotation list is empty (for
            text tasks on data that should be fully annotated); by default such records are
            kept (the official release has them) with ``has_annotations`` False.

    Raises:
        DatasetError: missing folder or files, malformed JSON (file and line named), an
            empty annotation list when ``require_annotations``.
    """
    folder = find_kitml_root(root)
    listed = [(p, m) for p in folder.iterdir() if (m := _ID.match(p.name))]
    check_inside((p for p, _ in listed), folder)
    ids = sorted(m.group(1) for _, m in listed)
    records = []
    for mid in progress(ids, desc="KIT-ML", unit="motion"):
        rec = read_record(folder, mid)
        if max_seconds is not None and rec.duration_s >= max_seconds:
            continue
        if require_annotations and not rec.has_annotations:
            raise DatasetError(f"{folder / f'{mid}_annotations.json'}: empty annotation list "
                               f"(motion {mid} has no description)")
        records.append(rec)
    return records


def kitml_summary(root: str | Path, max_seconds: float = 30.0) -> dict:
    """Counts and duration statistics (seconds) of all records and of the kept ones."""
    import numpy as np

    records = load_kitml(root, max_seconds=None)

    def stats(recs: list[KitMLRecord]) -> dict:
        d = np.array([r.duration_s for r in recs]) if recs else np.zeros(0)
        return {"motions": len(recs),
                "annotations": sum(len(r.annotations) for r in recs),
                "without_annotations": sum(not r.has_annotations for r in recs),
                "hours": float(d.sum() / 3600),
                "duration_s": {k: (float(f(d)) if len(d) else None) for k, f in
                               (("min", np.min), ("median", np.median), ("mean", np.mean),
                                ("max", np.max))}}

    kept = [r for r in records if r.duration_s < max_seconds]
    return {"root": str(find_kitml_root(root)), "max_seconds": max_seconds,
            "all": stats(records), "kept": stats(kept)}


def download_kitml(dest: str | Path, url: str = KITML_URL, sha256: str | None = None, *,
                   include_raw: bool = False, keep_archive: bool = True) -> Path:
    """Download and extract the KIT-ML release into ``dest/kitml``; return that folder.

    Resumes a broken download (``dest/<archive>.part``), checks ``sha256`` when given (KIT
    publishes none), extracts safely and atomically. Runs again are no-ops once the
    extracted folder exists.

    Args:
        dest: folder for the archive and the extracted data.
        url: release URL (default: the 2016-10-10 release, ``KITML_URL``).
        sha256: expected hex digest of the zip, if you have one.
        include_raw: also extract the ``*_raw.c3d`` marker files (most of the 3.9 GB).
        keep_archive: keep the zip after extraction.
    """
    dest = Path(dest)
    out = dest / EXTRACTED
    if out.is_dir():
        return out
    name = Path(urlparse(url).path).name
    archive = dest / (name if name.endswith(".zip") else KITML_ARCHIVE)
    download_file(url, archive, sha256=sha256, desc="KIT-ML")
    safe_extract(archive, out, keep=None if include_raw else
                 (lambda n: not n.lower().endswith(".c3d")))
    if not keep_archive:
        archive.unlink()
    return out


def load_annotations_tmr(path: str | Path) -> dict[str, dict]:
    """TMR's ``annotations_tmr.json``: id -> ``{"path", "duration", "texts", "segments"}``.

    ``texts`` is the list of sentences, ``segments`` the matching (start, end) seconds.
    Mirrored ids start with ``M``.
    """
    data = _read_json(Path(path))
    if not isinstance(data, dict):
        raise DatasetError(f"{path}: expected a JSON object keyed by motion id")
    out = {}
    for mid, entry in data.items():
        try:
            anns = entry["annotations"]
            out[mid] = {"path": entry.get("path"), "duration": float(entry["duration"]),
                        "texts": [a["text"] for a in anns],
                        "segments": [(float(a["start"]), float(a["end"])) for a in anns]}
        except (KeyError, TypeError, ValueError) as exc:
            raise DatasetError(f"{path}: entry {mid!r} is malformed ({exc!r})") from None
    return out


def caption_of(motion_path: str | Path) -> str | None:
    """"KIT-ML 00001: A person is walking forwards." for ``NNNNN_mmm.xml`` when TMR's
    ``annotations_tmr.json`` lies beside it; None otherwise (a caption is a nicety: an
    unreadable annotation file gives None too)."""
    motion_path = Path(motion_path)
    m = re.fullmatch(r"(\d{5})_mmm", motion_path.stem)
    ann = motion_path.parent / "annotations_tmr.json"
    if not m or not ann.is_file():
        return None
    try:
        texts = load_annotations_tmr(ann).get(m.group(1), {}).get("texts") or []
    except DatasetError:
        return None
    return f"KIT-ML {m.group(1)}: {texts[0]}" if texts else None


# Splits live in their own module; re-exported here as part of the KIT-ML API.
from motionlang.datasets.splits import load_split, load_splits, random_split, save_splits  # noqa: E402,F401

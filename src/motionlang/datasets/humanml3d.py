"""The HumanML3D folder layout (Guo et al. 2022), read as a motion-language dataset.

Layout of the public HumanML3D release and its KIT-ML version (``datasets.humanml3d_export``
writes the same)::

    DIR/new_joint_vecs/ID.npy   (T-1, 263 | 251) float32 rows (``features.h3d_vectors``)
    DIR/new_joints/ID.npy       (T-1, 22 | 21, 3) float32, the joints recovered from them
    DIR/texts/ID.txt            one caption a line: ``caption#word/POS word/POS ...#start#end``
    DIR/Mean.npy, DIR/Std.npy   per-column mean and grouped std of all the rows
    DIR/train.txt, val.txt, test.txt (all.txt)   one id a line
    DIR/.../M<ID>.npy           the mirrored copy of ID, its captions with left/right swapped

Bodies: ``smpl`` (``humanml3d:DIR``), the 22 SMPL joints at 20 fps in metres; ``kit``
(``kitml-h3d:DIR``), the 21 KIT joints (``features.joint_map``) at 12.5 fps in millimetres,
the unit of the public KIT-ML files. ``new_joints`` has as many frames as there are rows
(the public code saves ``recover_from_ric`` of the rows), one fewer than the source motion.

A caption with a time span (``start``/``end`` in seconds, not both 0) describes only
frames ``int(start * fps)`` to ``int(end * fps)``, as the public loader cuts them: each such
span is a record of its own, id ``ID@start-end``. :meth:`H3DRecord.load_motion` gives a
``Motion`` fitted to the stored joints (``kinematics.from_positions``: bone lengths held
constant, so joints that do not move rigidly, such as KIT's shoulders, come back within
about a centimetre); :meth:`H3DRecord.load_joints` gives the stored joints themselves.
"""
from __future__ import annotations

import math
import tokenize
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from motionlang.errors import DatasetError, MotionlangError
from motionlang.features.h3d_vectors import H3D_BODIES, H3DBody, vectors_to_joints
from motionlang.kinematics.from_positions import motion_from_positions
from motionlang.utils.limits import check, check_file, check_motion
from motionlang.utils.paths import check_inside

VECS, JOINTS, TEXTS = "new_joint_vecs", "new_joints", "texts"
SPLITS = ("train", "val", "test")
PREFIXES = {"humanml3d:": "smpl", "kitml-h3d:": "kit"}   # as in sources.KINDS: for hints
#: joint positions farther than this from the origin (metres) are refused as corrupt
MAX_METRES = 1e6

def format_caption_line(caption: str, tokens: list[str], start: float = 0.0,
                        end: float = 0.0) -> str:
    """One ``texts/ID.txt`` line (no newline); '#' and line breaks in the caption become
    spaces. ``start = end = 0`` means the whole motion."""
    clean = " ".join(caption.replace("#", " ").split())
    return f"{clean}#{' '.join(tokens)}#{float(start)}#{float(end)}"


def parse_caption_line(line: str, where: str = "caption") -> tuple[str, list[str], float, float]:
    """A ``texts/ID.txt`` line -> (caption, tokens, start, end); a bare caption has no tokens
    and no span; a NaN time is 0, as in the public loader."""
    parts = line.strip().split("#")
    tokens = parts[1].split() if len(parts) > 1 else []
    times = []
    for s in parts[2:4]:
        try:
            t = float(s)
        except ValueError:
            raise DatasetError(f"{where}: time {s[:40]!r} is not a number") from None
        times.append(0.0 if math.isnan(t) else t)
    start, end = (times + [0.0, 0.0])[:2]
    if not (math.isfinite(start) and math.isfinite(end)) or start < 0 or end < 0:
        raise DatasetError(f"{where}: time span {start:g}-{end:g} is not two finite times "
                           ">= 0")
    if end < start:
        raise DatasetError(f"{where}: time span {start:g}-{end:g} ends before it starts")
    return parts[0].strip(), tokens, start, end


@dataclass
class H3DRecord:
    """One motion (or one captioned span of it) of a HumanML3D-layout folder.

    Attributes:
        id: file stem, ``ID@start-end`` for a span. path: the file read (new_joints, else
        new_joint_vecs). annotations: captions. body: the layout's body. split: from the
        split files, or None. span: (start, end) seconds, or None for the whole motion.
        meta: ``{"h3d_id", "tokens": [[word/POS, ...] per caption]}``.
    """

    id: str
    path: Path
    annotations: list[str]
    body: H3DBody
    split: str | None = None
    span: tuple[float, float] | None = None
    meta: dict = field(default_factory=dict)

    @property
    def has_annotations(self) -> bool:
        return bool(self.annotations)

    def _cut(self, x: np.ndarray) -> np.ndarray:
        if self.span is None:
            return x
        fps, n = self.body.fps, len(x)   # a huge time (1e308 s) is past the end, not inf
        return x[int(min(self.span[0] * fps, n)):int(min(self.span[1] * fps, n))]

    def _load(self, path: Path, shape: tuple[int, ...]) -> np.ndarray:
        declared, _ = _header(path)
        if declared[1:] != shape or not declared[:1] or declared[0] < 1:
            raise DatasetError(f"{path}: expected (N >= 1, {', '.join(map(str, shape))}) for "
                               f"the {self.body.name} body, got {declared}")
        # the rows as float64, their joints and the Motion fitted to them
        check_motion(path, declared[0], self.body.n_joints, 2 * self.body.dim)
        x = _npy(path)
        if not np.isfinite(x).all():
            raise DatasetError(f"{path}: non-finite values (NaN or inf)")
        return x

    def load_vectors(self) -> np.ndarray:
        """(N, D) rows in the files' unit (metres for SMPL, millimetres for KIT); a span's
        rows are cut out of the motion's, as the public loader does."""
        cut = self._cut(self._load(self.path.parent.parent / VECS / self.path.name,
                                   (self.body.dim,)))
        if not len(cut):
            raise DatasetError(f"{self.path}: span {self.span} holds no frames")
        return cut

    def load_joints(self) -> np.ndarray:
        """(N, J, 3) metres, Y up: ``new_joints`` (or the joints recovered from the rows);
        a span's frames are cut out of the whole motion's, in its place."""
        if self.path.parent.name == JOINTS:
            p = self._load(self.path, (self.body.n_joints, 3))
        else:
            rows = self._load(self.path, (self.body.dim,))
            p = vectors_to_joints(rows, self.body)
        p = self._cut(p)
        if not len(p):
            raise DatasetError(f"{self.path}: span {self.span} holds no frames")
        p = np.asarray(p, dtype=float) * self.body.unit
        if not np.isfinite(p).all() or np.abs(p).max() > MAX_METRES:
            raise DatasetError(f"{self.path}: joint positions beyond {MAX_METRES:g} m or "
                               "not finite")
        return p

    def load_motion(self):
        """A ``Motion`` fitted to :meth:`load_joints` (``motion_from_positions``); the KIT
        body carries its identity joint map, so ``positions21`` works on it."""
        b = self.body
        joints = self.load_joints()
        try:
            motion = motion_from_positions(joints, b.fps, b.joint_names, b.parents, name=self.id)
        except MotionlangError as exc:  # e.g. a bone of length 0 in every frame
            raise DatasetError(f"{self.path}: {exc}") from None
        motion.source_format = "humanml3d"
        motion.meta.update(dataset=f"h3d-{b.name}", annotations=list(self.annotations))
        if b.name == "kit":
            motion.meta["joint_map"] = {"name": "kit21", "joints":
                                        {n: n for n in b.joint_names}}
        return motion


def _header(path: Path) -> tuple[tuple[int, ...], np.dtype]:
    """(shape, dtype) an ``.npy`` file declares, checked against its size and refused
    unless it holds plain numbers (no objects: nothing is unpickled)."""
    from numpy.lib import format as npy_format
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            version = npy_format.read_magic(fh)
            read = {(1, 0): npy_format.read_array_header_1_0,
                    (2, 0): npy_format.read_array_header_2_0}.get(version)
            if read is None:
                raise ValueError(f"unsupported .npy version {version}")
            shape, _, dtype = read(fh)
            offset = fh.tell()
    except FileNotFoundError:
        raise DatasetError(f"{path}: missing") from None
    except (OSError, ValueError, EOFError, TypeError, SyntaxError, OverflowError,
            RecursionError, tokenize.TokenError) as exc:  # a header numpy cannot parse
        why = "unterminated header" if isinstance(exc, tokenize.TokenError) else \
            " ".join(str(exc).split())[:200]
        raise DatasetError(f"{path}: not a readable .npy file ({why})") from None
    if dtype.kind not in "fiu" or dtype.fields is not None or dtype.subdtype is not None:
        raise DatasetError(f"{path}: holds {dtype.str} values, not real numbers")
    need = math.prod(shape) * dtype.itemsize
    if need > size - offset:
        raise DatasetError(f"{path}: header declares {shape} ({need:,} bytes of data), the "
                           f"file holds {max(size - offset, 0):,} (truncated or corrupt)")
    return tuple(shape), dtype


def _npy(path: Path, header_only: bool = False):
    """An ``.npy`` file's numbers (``header_only``: its declared shape, nothing read)."""
    shape, _ = _header(path)
    if header_only:
        return shape
    check(path, "max_memory_bytes", 8 * math.prod(shape), "memory needed to read it")
    try:
        return np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, TypeError) as exc:
        raise DatasetError(f"{path}: cannot read ({' '.join(str(exc).split())[:200]})") \
            from None


def _text(path: Path) -> str:
    """A caption or split file as text: UTF-8 (a byte-order mark allowed)."""
    check_file(path, parse_factor=10.0)
    try:
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DatasetError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise DatasetError(f"{path}: cannot read ({exc.strerror or exc})") from None


def _ids(root: Path) -> list[str]:
    files = [p for d in (VECS, JOINTS) if (root / d).is_dir() for p in (root / d).glob("*.npy")]
    check_inside(files, root)
    return sorted({p.stem for p in files})


def _splits(root: Path) -> dict[str, str]:
    out = {}
    for name in SPLITS:
        path = root / f"{name}.txt"
        if path.is_file():
            for line in _text(path).split():
                out.setdefault(line.strip(), name)
    return out


def _check_split_covers(root: Path, ids: list[str], split: dict[str, str]) -> None:
    """Split files that leave motions out are an error naming them: the training code
    would otherwise fall back to a random split, which puts the published test motions in
    training. A folder without split files is split at random, as any other."""
    if not split:
        return
    missing = [i for i in ids if i not in split]
    if missing:
        files = ", ".join(f"{n}.txt" for n in SPLITS if (root / f"{n}.txt").is_file())
        shown = ", ".join(missing[:10]) + (f", ... ({len(missing)} in all)"
                                           if len(missing) > 10 else "")
        raise DatasetError(f"{root}: the split files ({files}) do not list motion(s) {shown}; "
                           "add them to a split file, or remove every split file for a "
                           "random split")


def _check_body(root: Path, mid: str, body: H3DBody) -> None:
    """Fail early, with the right prefix named, when the folder holds the other body."""
    for folder, axis, want, what in ((VECS, -1, body.dim, "numbers a row"),
                                     (JOINTS, -2, body.n_joints, "joints")):
        path = root / folder / f"{mid}.npy"
        if not path.is_file():
            continue
        shape = _npy(path, header_only=True)
        got = shape[axis] if len(shape) >= -axis else None
        if got != want:
            size = "dim" if folder == VECS else "n_joints"
            other = [p for p, b in PREFIXES.items() if getattr(H3D_BODIES[b], size) == got]
            hint = f"; use {other[0]}{root}" if other else ""
            raise DatasetError(f"{path}: {got} {what}, not the {want} of the {body.name} "
                               f"body{hint}")


def _read_texts(path: Path) -> list[tuple[str, list[str], float, float]]:
    if not path.is_file():
        return []
    lines = _text(path).splitlines()
    return [parse_caption_line(line, f"{path}:{i}") for i, line in enumerate(lines, 1)
            if line.strip() and line.split("#")[0].strip()]


def _records_of(root: Path, mid: str, body: H3DBody, split: str | None) -> list[H3DRecord]:
    joints = root / JOINTS / f"{mid}.npy"
    path = joints if joints.is_file() else root / VECS / f"{mid}.npy"
    whole, spans = H3DRecord(mid, path, [], body, split, meta={"h3d_id": mid, "tokens": []}), {}
    for caption, tokens, start, end in _read_texts(root / TEXTS / f"{mid}.txt"):
        if start == 0.0 and end == 0.0:
            rec = whole
        else:
            rec = spans.setdefault((start, end), H3DRecord(
                f"{mid}@{start:g}-{end:g}", path, [], body, split, (start, end),
                {"h3d_id": mid, "tokens": []}))
        rec.annotations.append(caption)
        rec.meta["tokens"].append(tokens)
    return [whole, *spans.values()]


def load_h3d(root: str | Path, body: str = "smpl", *, mirrored: bool = False,
             max_seconds: float | None = None) -> list[H3DRecord]:
    """Records of a HumanML3D-layout folder, sorted by id (spans after their motion).

    Args:
        body: ``"smpl"`` (HumanML3D) or ``"kit"`` (its KIT-ML version).
        mirrored: keep the ``M<ID>`` copies whose original is there too (default off: a
            random split by id would put copies of test motions in training).
        max_seconds: drop motions longer than this (reads each file's header).

    Raises:
        DatasetError: no such folder, no ``new_joint_vecs``/``new_joints`` files, rows of
            the other body, a malformed caption time or span (not a number, infinite,
            negative, ending before it starts), a caption or split file that is not UTF-8, or
            an ``.npy`` header that is corrupt, truncated or not of real numbers (objects are
            never unpickled). Reading a record's rows or joints also refuses NaN and inf, and
            (``MotionFormatError``) files beyond ``utils.limits`` before allocating them.
    """
    root = Path(root)
    if body not in H3D_BODIES:
        raise DatasetError(f"unknown HumanML3D body {body!r} (smpl or kit)")
    spec = H3D_BODIES[body]
    if not root.is_dir():
        raise DatasetError(f"{root}: HumanML3D folder not found")
    ids = _ids(root)
    if not ids:
        raise DatasetError(f"{root}: no {VECS}/*.npy or {JOINTS}/*.npy files (not a "
                           "HumanML3D-layout folder)")
    _check_body(root, ids[0], spec)
    if not mirrored:
        present = set(ids)
        ids = [i for i in ids if not (i[:1] == "M" and i[1:] in present)]
    split = _splits(root)
    _check_split_covers(root, ids, split)
    records = [r for mid in ids for r in _records_of(root, mid, spec, split.get(mid))]
    if max_seconds is not None:
        records = [r for r in records if r.span is not None or
                   (_npy(r.path, header_only=True) or (0,))[0] / spec.fps <= max_seconds]
    return records


"""Reading BVH as it exists in the wild (conventions in :mod:`motionlang.formats.bvh`).

The file is read once: the HIERARCHY line by line, then the numbers of the MOTION block in
one pass of numpy's C parser straight from the file (no copy of the text is kept). Only if
that pass fails or disagrees with ``Frames:`` is the block scanned again, line by line, to
name the line, the frame and what is wrong.
"""
from __future__ import annotations

import io
import math
import warnings
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.formats.bvh_build import CHANNELS, MAX_ABS, build_motion
from motionlang.formats.units import resolve_unit
from motionlang.kinematics.motion import Motion
from motionlang.utils import limits

FPS_TOLERANCE = 2e-3  # 0.0333 s is 30 fps (30.03); 0.033 s is not (30.3)


# ------------------------------------------------------------------------------ hierarchy
def _shown(tok: str) -> str:
    """A token as an error line quotes it: the first 40 characters, or "binary data" for
    bytes that are not text (a terminal would print them as noise)."""
    odd = sum(c == "\ufffd" for c in tok)
    if any(c != "\ufffd" and not c.isprintable() for c in tok) or odd > 1 and 4 * odd > len(tok):
        return "binary data (this is not a text file)"
    return repr(tok[:40])


class _Tokens:
    """Whitespace tokens of the header, read lazily line by line with 1-based line numbers."""

    def __init__(self, path: Path, fh):
        self.path, self.fh = path, fh
        self.ln, self.buf = 0, []

    def _fill(self, what: str) -> None:
        while not self.buf:
            raw = self.fh.readline()
            if not raw:
                raise MotionFormatError(self.path, f"file ends early, expected {what}",
                                        line=max(self.ln, 1))
            self.ln += 1
            text = raw.decode("utf-8-sig" if self.ln == 1 else "utf-8", errors="replace")
            self.buf = text.split()[::-1]

    def next(self, what: str) -> tuple[str, int]:
        self._fill(what)
        return self.buf.pop(), self.ln

    def peek(self, what: str) -> str:
        self._fill(what)
        return self.buf[-1]

    def expect(self, word: str) -> int:
        tok, ln = self.next(repr(word))
        if tok.upper() != word.upper():
            raise MotionFormatError(self.path, f"expected {word!r}, got {_shown(tok)}", line=ln)
        return ln

    def number(self, what: str, integer: bool = False) -> float:
        tok, ln = self.next(what)
        try:
            v = int(tok) if integer else float(tok)
        except ValueError:
            raise MotionFormatError(self.path, f"malformed number {_shown(tok)} for {what}",
                                    line=ln) from None
        if not integer and not math.isfinite(v):
            raise MotionFormatError(self.path, f"non-finite {what}: {tok!r}", line=ln)
        if abs(v) > MAX_ABS:
            raise MotionFormatError(self.path, f"{what} out of range: {tok[:40]!r}", line=ln)
        return v


def _channel(tok: str) -> str | None:
    """Canonical channel name (``"xROTATION"`` -> ``"Xrotation"``), None if not one."""
    name = tok[:1].upper() + tok[1:].lower()
    return name if name in CHANNELS else None


def _parse_hierarchy(tk: _Tokens) -> list[dict]:
    """Nodes in file (depth-first) order: ``name``, ``parent``, ``offset`` (3,) in file
    units, ``channels`` (canonical names, file order), ``line``, ``end`` (End Site) and
    ``site_name`` (the name token of an End Site, None when it has none)."""
    tk.expect("HIERARCHY")
    max_joints = limits.current().max_joints
    nodes: list[dict] = []
    stack: list[int] = []   # the open nodes, outermost first
    tok, ln = tk.next("ROOT")
    if tok.upper() != "ROOT":
        raise MotionFormatError(tk.path, f"expected 'ROOT', got {_shown(tok)}", line=ln)
    while True:
        _open_node(tk, tok, ln, nodes, stack)
        child = _node_body(tk, nodes, stack)
        if child is None:
            return nodes
        tok, ln = child
        if len(nodes) > max_joints:
            limits.check(tk.path, "max_joints", len(nodes), "joint count", line=ln)


def _open_node(tk: _Tokens, tok: str, ln: int, nodes: list[dict], stack: list[int]) -> None:
    """Read a node's head (``ROOT``/``JOINT`` name, or ``End Site``) up to its ``{``, and
    append it to ``nodes`` as the innermost open node."""
    site_name = None
    if tok.upper() in ("ROOT", "JOINT"):
        if (tok.upper() == "ROOT") != (not stack):
            raise MotionFormatError(tk.path, f"unexpected {tok!r}", line=ln)
        if stack and nodes[stack[-1]]["end"]:
            raise MotionFormatError(tk.path, "an End Site cannot have children", line=ln)
        name, _ = tk.next("a joint name")
        kind = "joint"
    elif tok.upper() == "END":
        tk.expect("Site")
        if not stack or nodes[stack[-1]]["end"]:
            raise MotionFormatError(tk.path, "misplaced End Site", line=ln)
        if tk.peek("'{'") != "{":  # some exporters name their End Sites
            site_name = tk.next("an End Site name")[0]
        name, kind = site_name or f"{nodes[stack[-1]]['name']}_end", "end"
    else:
        raise MotionFormatError(tk.path, f"unexpected {_shown(tok)} in HIERARCHY", line=ln)
    tk.expect("{")
    nodes.append({"name": name, "parent": stack[-1] if stack else -1, "offset": None,
                  "channels": [], "line": ln, "end": kind == "end", "site_name": site_name})
    stack.append(len(nodes) - 1)


def _node_body(tk: _Tokens, nodes: list[dict], stack: list[int]) -> tuple[str, int] | None:
    """Read OFFSETs, CHANNELS and closing braces until a child node starts (its first token
    and line are returned) or the root closes (None)."""
    while True:
        tok, ln = tk.next("'}'")
        up = tok.upper()
        node = nodes[stack[-1]]
        if up == "OFFSET":
            node["offset"] = np.array([tk.number("OFFSET") for _ in range(3)])
        elif up == "CHANNELS":
            if node["end"]:
                raise MotionFormatError(tk.path, "End Site cannot have CHANNELS", line=ln)
            node["channels"] = _channel_list(tk, ln)
        elif tok == "}":
            if node["offset"] is None:
                raise MotionFormatError(tk.path, f"{node['name']!r} has no OFFSET", line=ln)
            stack.pop()
            if not stack:
                return None
        else:
            return tok, ln


def _channel_list(tk: _Tokens, ln: int) -> list[str]:
    """The count and canonical names after ``CHANNELS`` (at most 6, none twice)."""
    n = int(tk.number("the channel count", integer=True))
    if not 0 <= n <= 6:
        raise MotionFormatError(tk.path, f"bad channel count {n}", line=ln)
    raw = [tk.next("a channel name")[0] for _ in range(n)]
    chans = [_channel(c) for c in raw]
    if None in chans or len(set(chans)) != n:
        raise MotionFormatError(tk.path, f"bad channel list {raw}", line=ln)
    return chans


# ------------------------------------------------------------------------------ frames
def _read_frames(path: Path, fh, first_line: int, n_frames: int, C: int) -> np.ndarray:
    """(n_frames, C) channel values from ``fh`` (positioned at line ``first_line``)."""
    start = fh.tell()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "input contained no data"
        try:
            # one row more than declared is enough to tell that there are too many
            data = np.loadtxt(fh, dtype=float, comments=None, ndmin=2, max_rows=n_frames + 1)
        except Exception:  # noqa: BLE001 - whatever it is, the scan below names it exactly
            data = None
    # NaN fails both comparisons, inf the range; no (T, C) temporaries
    if data is not None and C > 0 and data.shape == (n_frames, C) and \
            -MAX_ABS <= data.min() and data.max() <= MAX_ABS:
        return data
    fh.seek(start)
    return _scan_frames(path, fh, first_line, n_frames, C)


def _scan_frames(path: Path, fh, first_line: int, n_frames: int, C: int) -> np.ndarray:
    """The slow, exact reading: one line at a time, raising on the first problem."""
    rows: list[np.ndarray] = []
    ln = first_line - 1
    for raw in fh:
        ln += 1
        toks = raw.split()
        if not toks:
            continue
        t = len(rows)
        if t >= n_frames:
            raise MotionFormatError(path, f"more frame lines than 'Frames: {n_frames}'", line=ln)
        if len(toks) != C:
            raise MotionFormatError(path, f"frame {t} has {len(toks)} values, expected {C}",
                                    line=ln)
        try:
            row = np.array([float(x) for x in toks])
        except ValueError:
            bad = next(x for x in toks if not _is_float(x)).decode("utf-8", errors="replace")
            raise MotionFormatError(path, f"malformed number {bad[:40]!r}", line=ln) from None
        if not np.all(np.isfinite(row)):
            raise MotionFormatError(path, "non-finite value (NaN or inf)", line=ln, frame=t)
        if np.abs(row).max(initial=0.0) > MAX_ABS:
            raise MotionFormatError(path, "value out of range", line=ln, frame=t)
        rows.append(row)
    if len(rows) < n_frames:
        raise MotionFormatError(path, f"file truncated: {len(rows)} of {n_frames} frames",
                                line=max(ln, 1))
    return np.array(rows)


def _is_float(x: bytes) -> bool:
    try:
        float(x)
        return True
    except ValueError:
        return False


def _open(path: Path):
    """A binary file object; files with old-Mac ``\\r``-only line ends are read whole and
    given ``\\n`` (line-by-line reading needs them)."""
    limits.check_file(path)
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    head = fh.read(1 << 16)
    if b"\r" in head and b"\n" not in head:
        with fh:
            return io.BytesIO((head + fh.read()).replace(b"\r", b"\n"))
    fh.seek(0)
    return fh


def _header(tk: _Tokens) -> tuple[list[dict], int, float, float]:
    """``(nodes, frames, frame time s, fps)`` of the header ``tk`` reads, up to the first
    frame's line."""
    path = tk.path
    nodes = _parse_hierarchy(tk)
    tk.expect("MOTION")
    tk.expect("Frames:")
    n_frames = int(tk.number("the frame count", integer=True))
    tk.expect("Frame")
    ln = tk.expect("Time:")
    dt = tk.number("the frame time")
    if tk.buf:
        raise MotionFormatError(path, "unexpected text after the frame time", line=ln)
    if dt <= 0:
        raise MotionFormatError(path, f"frame time must be positive, got {dt}", line=ln)
    if n_frames <= 0:
        raise MotionFormatError(path, "no frames (Frames: 0)", line=ln)
    fps = 1.0 / dt
    if not math.isfinite(fps):
        raise MotionFormatError(path, f"frame time too small: {dt}", line=ln)
    if round(fps) >= 1 and abs(fps - round(fps)) <= FPS_TOLERANCE * fps:
        fps = float(round(fps))   # 0.0333333 s -> 30 fps, not 30.00003
    return nodes, n_frames, dt, fps


def bvh_header(path: str | Path) -> tuple[tuple[str, ...], float]:
    """``(joint names in file order, fps)`` of a BVH file, from its header alone (none of
    its frames are read).

    Raises:
        MotionFormatError: as :func:`read_bvh`, for the header.
    """
    path = Path(path)
    with _open(path) as fh:
        nodes, _, _, fps = _header(_Tokens(path, fh))
    return tuple(n["name"] for n in nodes if not n["end"]), fps


def read_bvh(path: str | Path, unit: float | str | None = None) -> Motion:
    """Read a BVH file.

    Args:
        unit: metres per file length unit (or ``"m"``, ``"cm"``, ``"mm"``, ``"inch"``);
            decided from the body when None (:mod:`motionlang.formats.units`).

    Returns:
        Motion with a Y-up skeleton named ``"bvh:<stem>"``. ``meta`` keys (see
        :mod:`motionlang.formats.bvh` for their exact meaning): ``path``, ``frame_time``,
        ``unit``, ``stature_m``, ``unit_note`` (only when the unit was not detected),
        ``bvh_root_channels``, ``bvh_hierarchy``, ``bvh_position_spread_m``.

    Raises:
        MotionFormatError: on malformed content, naming the file and line, or a file or
            motion beyond the limits (``utils.limits``), checked before reading the numbers.
        ValueError: an unknown ``unit``.
    """
    path = Path(path)
    given = None if unit is None else resolve_unit(unit)
    with _open(path) as fh:
        tk = _Tokens(path, fh)
        nodes, n_frames, dt, fps = _header(tk)
        C = sum(len(n["channels"]) for n in nodes)
        limits.check_motion(path, n_frames, len(nodes), C)  # before asking for the memory
        data = _read_frames(path, fh, tk.ln + 1, n_frames, C)
    motion = build_motion(path, nodes, data, fps, given)
    motion.meta["frame_time"] = dt
    return motion

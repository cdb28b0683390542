"""Motion composed from a library's own clips: ``motionlang generate "a person walks forward,
then sits down" --library library.idx -o out.bvh`` (``ml.generate(..., library=...)``).

How animators already work (motion graphs; retrieval-augmented generation): the sentence is
cut into its parts where it says one thing after another ("then", "after that", "followed
by", ";"), each part is searched in the library (``library.search``: the takes the analysis
sees doing it first), and the best hit of each becomes a clip. The clips are laid one after
the other on the 21-joint body: each turned about the vertical so that it starts facing the
way the last one ends, and moved so that its root starts where the last one's is, its feet
on the same floor. Where they meet is searched for, as a motion graph's transitions are:
the frames near the end of one clip and the start of the next whose poses and foot speeds
are most alike (:func:`best_cut`). Each join is an in-between of :data:`JOIN` seconds where
the last frames of one clip and the first of the next overlap: the root-relative poses are
blended in their own headings with a smooth weight while the heading turns from the one to
the other, the root path follows the blend of the two, every frame is put back on one
set of bone lengths (a blend of two poses shortens the bones between them), and the feet
are then held where they are planted (``features.foot_lock.lock_feet``, footskate cleanup) so that a join does
not slide. Every clip's source file and time span is kept: a user knows whose motion it is.
"""
from __future__ import annotations

import json
import re
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motionlang.analysis import analyse_positions, check_sentence
from motionlang.analysis.check import not_shown_line, unmet
from motionlang.analysis.words import actions_named
from motionlang.errors import MotionlangError
from motionlang.features.body21 import body21, stature21, uniform_bones21
from motionlang.features.foot_lock import lock_feet
from motionlang.features.joint_map import bone_lengths21
from motionlang.features.positions import facing_yaw
from motionlang.features.root import from_heading, increments, integrate, to_heading
from motionlang.library.search import Library
from motionlang.rendering.output import check_result_path, write_result
from motionlang.utils.atomic import atomic_write

#: hits of each later part tried for the cheapest join
CANDIDATES = 3
#: frames a second of the composed motion
FPS = 30.0
#: seconds two clips overlap at a join
JOIN = 0.5
#: seconds of a clip at most (a long walk of a take is cut to this)
MAX_CLIP = 4.0
#: seconds taken before a hit the analysis found: sitting down starts before the sitting
LEAD = 1.0
#: seconds at the end of a clip and at the start of the next searched for the frames most
#: alike to join at (a motion graph's transition point)
SEARCH = (1.0, 0.5)
#: seconds a clip goes on past its action where the take allows: the join is searched for
#: and blended after the action, never over its last frames (a jump keeps its landing)
TAIL = JOIN + SEARCH[0]
#: where a sentence says one thing after another
_PARTS = re.compile(r"\s*(?:,?\s*(?:and\s+)?then\b|,?\s*after that\b|,?\s*followed by\b|;|"
                    r",?\s*and finally\b|,?\s*afterwards\b)\s*,?\s*", re.IGNORECASE)
_SUBJECT = re.compile(r"^(?:a|an|the|some)\s+\w+|^(?:someone|somebody|he|she|they)\b", re.I)

METHOD = ("clips of the library found by search, turned and moved to follow one another, "
          f"overlapping {JOIN:g} s at each join where their poses are blended and the root "
          "path follows, then the planted feet held (footskate cleanup)")


def parts(text: str) -> list[str]:
    """The parts of a sentence that says one thing after another, each a query with the
    sentence's subject ("a person walks forward, then sits down" -> ["a person walks
    forward", "a person sits down"]).

    Raises:
        MotionlangError: a sentence with no words.
    """
    if not text.split():
        raise MotionlangError("the sentence to compose is empty")
    pieces = [p.strip(" ,.") for p in _PARTS.split(text) if p and p.strip(" ,.")]
    m = _SUBJECT.match(pieces[0]) if pieces else None
    subject = m.group(0) if m else "a person"
    return [p if _SUBJECT.match(p) else f"{subject} {p}" for p in pieces]


@dataclass
class Clip:
    """One part's clip: the part, the take it came from (path under the indexed folder), its
    span in seconds there, why search chose it (empty: the learned model alone) and the
    span, seconds in the take, where the analysis saw the part's action (a join never cuts
    into it)."""

    part: str
    file: str
    start: float
    end: float
    why: str = ""
    shows: tuple[float, float] | None = None

    def kept(self, fps: float = FPS) -> tuple[int, int] | None:
        """The frames of the clip (at ``fps``) from the action's first to its last (an
        action that goes on past the clip's end, a long walk cut to :data:`MAX_CLIP`, to
        the clip's last frame: the join then comes at its end, the action still going)."""
        if self.shows is None:
            return None
        length = self.end - self.start
        lo, hi = (min(max(0.0, t - self.start), length) for t in self.shows)
        return int(lo * fps), int(np.ceil(max(lo, hi) * fps))


@dataclass
class Composed:
    """A composed motion: global 21-joint positions (T, 21, 3) metres at ``fps``, its clips
    in order, and how it was made (for the output's sidecar)."""

    positions: np.ndarray
    fps: float
    clips: list[Clip] = field(default_factory=list)
    method: str = METHOD
    joins: list[int] = field(default_factory=list)   # the first frame of each overlap

    def sidecar(self, text: str, index: str) -> dict:
        """What the output's ``.json`` sidecar records."""
        return {"text": text, "method": self.method, "index": index, "fps": self.fps,
                "frames": len(self.positions), "clips": [asdict(c) for c in self.clips],
                "joins": [round(j / self.fps, 3) for j in self.joins]}


def _resampled(p: np.ndarray, fps: float, to: float) -> np.ndarray:
    """(T, 21, 3) at ``fps`` -> the same span at ``to`` Hz (linear)."""
    if len(p) < 2 or abs(fps - to) < 1e-6:
        return p
    t = np.arange(len(p)) / fps
    new = np.arange(0.0, t[-1] + 1e-9, 1.0 / to)
    flat = p.reshape(len(p), -1)
    return np.stack([np.interp(new, t, flat[:, j]) for j in range(flat.shape[1])],
                    axis=1).reshape(len(new), 21, 3)


def candidates(lib: Library, part: str, used: set[tuple[str, float]],
               k: int = CANDIDATES) -> list[tuple[Clip, tuple[str, float]]]:
    """The clips one part could be, best first, each with its hit's key for ``used``: up
    to ``k`` hits whose reason shows the part's actions (else the first hit), none a span
    already used."""
    hits = lib.search(part, k=10)
    if not hits:
        raise MotionlangError(f"{lib.where}: nothing in the library for {part!r}")
    asked = bool(actions_named(part))
    picks = [h for h in hits if (h.why or not asked) and (h.file, h.start) not in used][:k]
    out = []
    for pick in picks or hits[:1]:
        if pick.why and pick.shows is not None:
            start = max(0.0, pick.start - LEAD)
            if pick.shows[1] <= start + MAX_CLIP:   # the clip goes on past the action
                end = min(lib.entry_named(pick.file).duration, pick.shows[1] + TAIL)
            else:   # a long action is cut, and joined inside it
                end = start + MAX_CLIP
            clip = Clip(part, pick.file, round(start, 3), round(end, 3), pick.why, pick.shows)
        else:
            clip = Clip(part, pick.file, round(pick.start, 3),
                        round(min(pick.end, pick.start + MAX_CLIP), 3), pick.why)
        out.append((clip, (pick.file, pick.start)))
    return out


def _clip_positions(lib: Library, clip: Clip, stature: float | None) -> np.ndarray:
    """(T, 21, 3) of a clip at :data:`FPS`, feet on the floor, starting at the origin facing
    +Z, scaled to ``stature`` m (the first clip's: one body all through)."""
    take = lib.take_named(clip.file)
    cut = take.between(clip.start, clip.end)
    return _resampled(body21(cut, stature=stature), float(take.fps), FPS)


def _shows(part: str, p: np.ndarray) -> bool:
    """Whether ``p`` (T, 21, 3) at :data:`FPS` does every action ``part`` names as it
    says (``ActionCheck.met``; an action the analysis has no detector for counts as
    done)."""
    try:
        return all(c.met is not False for c in check_sentence(part, analyse_positions(p, FPS)))
    except MotionlangError:
        return False


def _lost(part: str, last: str | None, joined: np.ndarray, at: int, end: int, offset: int,
          cost: float) -> tuple[bool, bool, float]:
    """How a candidate join is ranked: whether ``part``'s action is lost from the joined
    motion (T, 21, 3) after ``at``, whether the ``last`` part's is lost from its clip
    (``joined[offset:end]``, up to the blend's end) and the join's cost."""
    before = last is not None and not _shows(last, joined[max(0, offset):end])
    return not _shows(part, joined[at:]), before, cost


def _smooth(n: int) -> np.ndarray:
    x = (np.arange(n) + 0.5) / n
    return x * x * (3 - 2 * x)


def _pose(p: np.ndarray) -> np.ndarray:
    """(T, 21, 3) -> each frame's joints relative to its root, in its own heading."""
    rel = p - p[:, :1] * np.array([1.0, 0.0, 1.0])
    return to_heading(rel, facing_yaw(p)[:, None])


def overlap_frames(overlap: int, na: int, nb: int) -> int:
    """The frames a join of a clip of ``na`` frames to one of ``nb`` overlaps, at most
    ``overlap``: each keeps a frame of its own."""
    return max(1, min(overlap, na - 1, nb - 1))


def best_cut(a: np.ndarray, b: np.ndarray, overlap: int, fps: float = FPS
             ) -> tuple[int, int]:
    """``(end, start)``: join ``a[:end]`` to ``b[start:]`` where the frames are most alike
    (:func:`cut_cost`)."""
    end, start, _ = cut_cost(a, b, overlap, fps)
    return end, start


def cut_cost(a: np.ndarray, b: np.ndarray, overlap: int, fps: float = FPS, *,
             keep: int = 0, reach: int | None = None) -> tuple[int, int, float]:
    """``(end, start, cost)`` of the best join of ``a[:end]`` to ``b[start:]``: the frames
    most alike (mean joint distance of the root-relative poses in their own heading, m, plus
    the joints' velocity difference, m a frame, so that a planted foot meets a planted
    foot), searched over :data:`SEARCH` seconds; the blend starts no earlier than ``a``'s
    frame ``keep`` and ``b`` starts no later than its frame ``reach`` (the spans where the
    analysis saw each part's action stay whole: where a clip leaves no room, the join
    comes as close to that as it can)."""
    if len(a) < 2 or len(b) < 2:
        raise MotionlangError(f"a join needs two frames of each clip, got {len(a)} and "
                              f"{len(b)}")
    overlap = overlap_frames(overlap, len(a), len(b))
    na, nb = int(SEARCH[0] * fps), int(SEARCH[1] * fps)
    ends = np.arange(min(len(a), max(overlap + 1, len(a) - na, keep + overlap)), len(a) + 1)
    last = max(1, min(nb, len(b) - overlap))
    if reach is not None:   # the blended frames of b too come before its action
        last = max(1, min(last, reach - overlap + 1))
    starts = np.arange(0, last)
    pa, pb = _pose(a), _pose(b)
    # velocities in each frame's own heading, as the poses are: the clips face anywhere
    va = to_heading(np.gradient(a, axis=0), facing_yaw(a)[:, None]) * fps
    vb = to_heading(np.gradient(b, axis=0), facing_yaw(b)[:, None]) * fps
    cost = np.empty((len(ends), len(starts)))
    for i, e in enumerate(ends):
        f = e - overlap   # a's first overlapping frame meets b's start
        d = np.linalg.norm(pa[f] - pb[starts], axis=-1).mean(axis=-1)
        dv = np.linalg.norm(va[f][None] - vb[starts], axis=-1).mean(axis=-1) / fps
        cost[i] = d + dv
    best_i, best_j = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return int(ends[best_i]), int(starts[best_j]), float(cost[best_i, best_j])


def _local(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T, 21, 3) -> the pose in its own heading about the root's ground point (T, 21, 3),
    the root's ground path (T, 2) as (x, z) and the heading (T,) radians, unwrapped."""
    yaw = np.unwrap(facing_yaw(p))
    ground = p[:, 0, [0, 2]]
    at_root = p - np.stack([ground[:, 0], np.zeros(len(p)), ground[:, 1]], axis=1)[:, None]
    return to_heading(at_root, yaw[:, None]), ground, yaw


def _placed(local: np.ndarray, ground: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """:func:`_local`'s inverse: (T, 21, 3) world positions."""
    root = np.stack([ground[:, 0], np.zeros(len(ground)), ground[:, 1]], axis=1)[:, None]
    return from_heading(local, yaw[:, None]) + root


def join(a: np.ndarray, b: np.ndarray, overlap: int) -> np.ndarray:
    """``b`` (T, 21, 3) laid after ``a`` (T, 21, 3), ``a``'s last ``overlap`` frames
    blended with ``b``'s first (module docstring); where ``b`` starts in the world does not
    matter."""
    overlap = overlap_frames(overlap, len(a), len(b))
    at = len(a) - overlap
    la, ga, ya = _local(a[at:])
    lb, gb, yb = _local(b[:overlap])
    w = _smooth(overlap)
    # the root's steps and turns (in each clip's own heading) are blended, not its places:
    # the blend then carries a walk's speed or a spin's turning over into the next clip,
    # where blending positions would pull the root back and fold two bodies facing apart
    # through each other
    va, ta = increments(ga, ya)
    vb, tb = increments(gb, yb)
    ground, yaw = integrate((1 - w)[:, None] * va + w[:, None] * vb, (1 - w) * ta + w * tb,
                            (ga[0, 0], ga[0, 1], ya[0]))
    mixed = _placed((1 - w)[:, None, None] * la + w[:, None, None] * lb, ground, yaw)
    # the rest of b goes on from b's own last overlapping frame, laid where the blend ended
    turn = yaw[-1] - yb[overlap - 1]
    rest = b[overlap:] - np.array([gb[overlap - 1, 0], 0.0, gb[overlap - 1, 1]])
    rest = from_heading(rest, np.full(rest.shape[:2], turn)) + \
        np.array([ground[-1, 0], 0.0, ground[-1, 1]])
    return np.concatenate([a[:at], mixed, rest])


def compose(text: str, library: str | Path | Library, *, model: Any = None,
            overlap: float = JOIN) -> Composed:
    """A motion for ``text`` made of ``library``'s clips (an index file or an open
    :class:`Library`; ``model``: its model, if not the one it names).

    Raises:
        MotionlangError: an empty sentence, a missing or damaged index, a part nothing in
            the library matches, or a clip whose file no longer reads.
    """
    lib = library if isinstance(library, Library) else Library.open(library, model)
    used: set[tuple[str, float]] = set()
    frames = max(1, int(round(overlap * FPS)))
    out: np.ndarray | None = None
    joins: list[int] = []
    clips: list[Clip] = []
    offset = 0   # where the last clip's first frame is in ``out``
    for part in parts(text):
        tried = []
        for clip, key in candidates(lib, part, used):
            if out is None:   # the first part: the hits in search's order
                p = _clip_positions(lib, clip, None)
                tried.append((0.0, clip, key, p, 0, 0, p, 0))
                continue
            shown = clips[-1].kept()
            reach = clip.kept()
            p = _clip_positions(lib, clip, stature21(out))
            end, start, cost = cut_cost(out, p, frames, keep=shown[1] + offset if shown else 0,
                                        reach=reach[0] if reach else None)
            at = end - overlap_frames(frames, end, len(p) - start)
            tried.append((cost, clip, key, p, end, start, join(out[:end], p[start:], frames), at))
        # of the hits that show the part, the one that joins the motion so far best (as a
        # motion graph takes its cheapest transition) where the part's action is still
        # there once joined and the last part's too, else the nearest to that
        last = clips[-1].part if clips else None
        pick = min(tried, key=lambda t: _lost(part, last, t[6], t[7], t[4], offset, t[0]))
        _, clip, key, p, end, start, out, at = pick
        used.add(key)
        if clips:
            joins.append(at)
            offset = at - start
        clips.append(clip)
    assert out is not None
    # a blend of two poses shortens the bones between them: every frame back on one body
    out = uniform_bones21(out, np.median(bone_lengths21(out), axis=0))
    return Composed(lock_feet(out, FPS), FPS, clips, joins=joins)


def compose_to(text: str, library: str | Path | Library, out: str | Path, *,
               model: Any = None, rig: Any = None) -> str:
    """Compose ``text`` (:func:`compose`) and write it to ``out`` (any format
    ``rendering.output.write_result`` writes; ``rig``: retargeted onto it) with the sidecar
    ``OUT.json`` listing the method and every clip; returns the lines that say so.

    Raises:
        MotionlangError: as :func:`compose`, or an output that cannot hold the motion.
    """
    out = Path(out)
    check_result_path(out, rig=rig is not None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # "no take shows it": the clips' reasons say so
        made = compose(text, library, model=model)
    note = write_result(made.positions, out, fps=made.fps, title=text, rig=rig)
    side = out.with_name(out.name + ".json")
    with atomic_write(side) as fh:
        fh.write(json.dumps(made.sidecar(text, str(library)), indent=1) + "\n")
    lines = [f"{len(made.positions)} frames at {made.fps:g} Hz -> {out}{note}",
             f"made of {len(made.clips)} clips of the library (listed in {side}):"]
    lines += [f"  {c.part!r}: {c.file} {c.start:.1f}-{c.end:.1f} s"
              + (f" ({c.why})" if c.why else " (the learned model's nearest)")
              for c in made.clips]
    try:
        missed = unmet(text, analyse_positions(made.positions, made.fps))
    except MotionlangError:   # a motion the analysis cannot read: nothing to say of it
        missed = []
    if missed:   # no take of the library shows it, or the join lost it
        lines.append(f"warning: {not_shown_line(missed)}")
    return "\n".join(lines)

"""One motion -> what its body does: every detector's findings, the main action, one grounded
sentence (terse or detailed), a timeline for a long take, and the evidence of each phrase.

The detectors (``posture``, ``locomotion``, ``limbs``) each report what they see; this module
decides what is worth saying. Each finding gets a salience (how much a reader would want to
hear it: a punch more than a reach, a long walk more than a short one, scaled by the finding's
confidence); findings that another one says better are dropped (a raise inside a wave, the
crouch before a jump, a turn the path of a walk already tells); the most salient few are said
in time order.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from motionlang.analysis.body import Body, pieces
from motionlang.analysis.dance import dances, said_by_dance
from motionlang.analysis.evidence import Finding, merge_series, overlap
from motionlang.analysis.limbs import limb_actions
from motionlang.analysis.locomotion import in_place, jumps, levels, travel, turns
from motionlang.analysis.posture import postures
from motionlang.analysis.sentences import CANNOT_TELL, LEVELS, MAX_CLAUSES, join, phrase
from motionlang.errors import MotionlangError

#: the detectors' version: raised whenever what they find changes, so that an index made
#: with older findings analyses its takes again on its next update
VERSION = 12
#: how much each label is worth saying, before confidence and duration
WEIGHT = {
    "dance": 3.2, "punch": 3.0, "kick": 3.0, "climb": 3.0, "hang": 2.6, "wave": 2.5, "clap": 2.5,
    "sit": 2.5, "lie": 2.5, "kneel": 2.5, "crawl": 2.8, "all_fours": 2.4, "squat": 2.3,
    "one_leg": 2.4, "crouch": 2.0, "jump": 2.2, "hop": 2.3, "run": 2.2, "walk": 1.8,
    "spin": 2.2, "turn": 1.2, "raise": 1.6, "touch_floor": 1.6, "bend": 1.3, "reach": 0.8,
    "arms_out": 0.9, "bow": 2.0, "step_up": 1.4, "step_down": 1.4, "stand": 0.3, "get_up": 1.0,
}
#: the coarse action each label names (what ``main_action`` reports)
ACTION = {"dance": "dance", "run": "run", "walk": "walk", "jump": "jump", "hop": "jump", "climb": "climb",
          "hang": "climb", "punch": "punch", "kick": "kick", "crouch": "crouch",
          "squat": "crouch", "sit": "sit", "lie": "lie", "kneel": "kneel", "crawl": "crawl",
          "all_fours": "crawl", "one_leg": "balance", "wave": "wave", "raise": "raise",
          "clap": "clap", "turn": "turn", "spin": "spin", "touch_floor": "bend",
          "bend": "bend", "bow": "bow", "reach": "reach", "arms_out": "arms_out", "step_up": "step",
          "step_down": "step", "stand": "stand", "get_up": "stand"}
LOW = ("sit", "lie", "kneel", "squat", "crouch", "all_fours", "crawl")
#: a timeline segment shorter than this (s) is taken into its neighbour
MIN_SEGMENT = 0.8
#: most cells a timeline is painted in (its resolution falls below 0.1 s past 10,000 s)
TIMELINE_CELLS = 100_000
#: wrist over shoulder (arm lengths) from which a raise is overhead, more than arms held out
OVERHEAD = 0.45
#: the events of a timeline: actions with a wind-up before them and a landing or recovery
#: after, which a timeline gives the seconds around them
EVENTS = ("jump", "hop", "kick", "punch")
#: seconds before and after an event that a timeline gives to it
EVENT_PAD = 0.6
#: seconds no finding names, between an event and anything else, that a timeline gives to
#: the event as well: standing still to gather for a jump, or after landing, belongs to the
#: jump, and a walk ends where the feet stop
GAP_REACH = 1.0


def salience(f: Finding) -> float:
    """How much a reader would want to hear ``f`` (module docstring)."""
    w = WEIGHT.get(f.label, 1.0) * f.confidence
    if (f.kind in ("posture", "locomotion") and f.label not in ("jump", "hop")) or \
            f.label == "dance":     # a stretch, worth more the longer it lasts
        return w * (0.4 + 0.6 * min(1.0, f.duration / 2.0))
    if f.label == "turn":
        return w * (1.3 if abs(f.detail.get("angle", 0)) >= 135 else 1.0)
    return w * min(1.0, 0.7 + 0.15 * f.count)


def _sides_meet(a: Finding, b: Finding) -> bool:
    return a.side is None or b.side is None or a.side == b.side or "both" in (a.side, b.side)


def prune(found: list[Finding]) -> list[Finding]:
    """Drop the findings that another finding says better (module docstring)."""
    keep = []
    for f in found:
        def covered(labels: tuple[str, ...], share: float = 0.3, sides: bool = False,
                    f: Finding = f) -> bool:
            return any(g is not f and g.label in labels and overlap(f, g) >= share *
                       max(f.duration, 1e-6) and (not sides or _sides_meet(f, g))
                       for g in found)
        lab = f.label
        if lab == "raise" and covered(("wave", "hang", "climb", "punch"), sides=True):
            continue
        if lab == "raise" and covered(("reach",), 0.5, sides=True) and not any(
                g.label == "raise" and g.side == "both" for g in found):
            continue    # an arm held out in front is said as a reach
        if lab == "reach" and covered(("punch", "hang", "climb"), sides=True):
            continue
        if lab == "bend" and covered(("touch_floor",)):
            continue
        if lab == "bow" and covered(("bend", "touch_floor", "crouch", "squat", "sit",
                                     "kneel"), 0.1):
            continue
        if lab in ("crouch", "squat", "bow") and (covered(("kneel", "sit")) or (
                f.duration < 1.5 and any(g.label in ("jump", "hop", "climb", "touch_floor")
                                         and g.start - f.end < 1.0 and g.end > f.start
                                         for g in found))):
            continue    # the dip before a jump, or the crouch of reaching down
        if lab == "one_leg" and covered(("kick", "hop", "hang", "climb"), 0.1):
            continue
        if lab == "hang" and covered(("climb",), 0.1):
            continue
        if f.kind == "level" and f.detail.get("direction") == "down" and any(
                g.label == "jump" and g.detail.get("direction") == "down" and
                g.start - f.end < 0.5 and f.start - g.end < 0.5 for g in found):
            continue    # the jump down says it
        if lab == "touch_floor" and covered(("crawl", "all_fours", "lie", "kneel"), 0.1):
            continue
        if lab == "turn" and abs(f.detail.get("angle", 0)) < 135 and \
                covered(("punch", "kick"), 0.3):
            continue    # the trunk turns with a strike
        if lab in ("turn", "spin") and any(
                g.label in ("walk", "run") and overlap(f, g) >= 0.5 * f.duration and (
                    g.detail.get("path") == "in a circle" or (
                        g.detail.get("path") != "straight" and
                        abs(f.detail.get("angle", 0)) < 135)) for g in found):
            continue    # the path of the walk says it
        if lab == "stand" and any(g.label != "stand" and g.kind != "turn" for g in found):
            continue
        if lab in ("wave", "clap") and covered(("punch",), 0.3):
            continue    # a boxer's guard moves the hands too
        if lab == "arms_out" and covered(("wave", "punch", "hang"), 0.1):
            continue
        if lab == "raise" and f.value < OVERHEAD and covered(("arms_out",), 0.5):
            continue    # arms held out level to the sides, not raised
        keep.append(f)
    return keep


def _series_of_squats(found: list[Finding]) -> list[Finding]:
    """Crouches and squats less than 1.5 s apart as one squat with its count ("squats 3
    times"): going down and up again and again is one action."""
    series = merge_series([f for f in found if f.label in ("crouch", "squat")])
    # a series is said as squats; one going down stays as it was found
    merged = [replace(f, label="squat") if f.count > 1 else f for f in series]
    return [f for f in found if f.label not in ("crouch", "squat")] + merged


def _get_ups(found: list[Finding], end: float) -> list[Finding]:
    """A "gets up" after each low posture that standing or travel follows."""
    out = []
    for f in found:
        if f.label not in LOW or f.end > end - 0.5:
            continue
        after = [g for g in found if g.label in ("stand", "walk", "run", "jump") and
                 0 <= g.start - f.end < 1.5]
        if after:
            out.append(Finding("posture", "get_up", f.end, min(end, f.end + 0.5),
                               "pelvis height after the low posture (standing = 1)", 1.0,
                               0.88, min(f.confidence, after[0].confidence)))
    return out


@dataclass(frozen=True)
class Analysis:
    """What a motion's body does (module docstring).

    Attributes:
        findings: every finding kept, in time order.
        duration: seconds of the take.
        leg, stature: the body's leg length and stature, metres.
    """

    findings: tuple[Finding, ...]
    duration: float
    leg: float
    stature: float

    def ranked(self) -> list[Finding]:
        """Findings by salience, most salient first."""
        return sorted(self.findings, key=lambda f: (-salience(f), f.start))

    def main(self) -> Finding | None:
        """The most salient finding, or None where nothing was found with confidence."""
        r = self.ranked()
        return r[0] if r else None

    def main_action(self) -> str | None:
        """The coarse action (``ACTION``) of :meth:`main`, or None."""
        m = self.main()
        return None if m is None else ACTION[m.label]

    def actions(self) -> set[str]:
        """Every coarse action found."""
        return {ACTION[f.label] for f in self.findings}

    def clauses(self, limit: int = MAX_CLAUSES) -> list[Finding]:
        """The findings a sentence says: the ``limit`` most salient, in time order, one per
        label (a second walk is the same phrase)."""
        chosen: list[Finding] = []
        for f in self.ranked():
            if len(chosen) >= limit:
                break
            if f.label == "stand" and chosen:
                continue
            same = [i for i, g in enumerate(chosen) if g.label == f.label]
            if same:      # one phrase per label: the sides and counts of both together
                g = chosen[same[0]]
                if f.kind == "limb" and f.side != g.side:
                    side = "both" if f.label in ("raise", "wave", "reach") else None
                    chosen[same[0]] = replace(g, side=side, count=g.count + f.count)
                continue
            chosen.append(f)
        return sorted(chosen, key=lambda f: f.start)

    def sentence(self, level: str = "terse", clauses: int | None = None) -> str:
        """One English sentence, or :data:`~motionlang.analysis.sentences.CANNOT_TELL`;
        ``clauses``: at most this many phrases (default: by ``level``)."""
        if level not in LEVELS:
            raise MotionlangError(f"sentence level must be one of {', '.join(LEVELS)}, got "
                                  f"{level!r}")
        said = self.explain(level, clauses)
        return join([text for text, _ in said]) if said else CANNOT_TELL

    def explain(self, level: str = "terse", clauses: int | None = None
                ) -> list[tuple[str, Finding]]:
        """(phrase, finding) for each phrase of :meth:`sentence`."""
        chosen = self.clauses(clauses or (MAX_CLAUSES if level == "terse" else
                                          MAX_CLAUSES + 2))
        return [(phrase(f, level=level, first=i == 0), f) for i, f in enumerate(chosen)]

    def within(self, start: float, end: float) -> Analysis:
        """The findings that fall mostly within [start, end), times kept; a repeated one
        (``count``) that the span holds only part of counts its share of the repeats (a
        4.4-s series of 3 spins, 1 s of it in the span: 1)."""
        inside = []
        for f in self.findings:
            held = max(0.0, min(end, f.end) - max(start, f.start))
            if held < 0.5 * min(max(f.duration, 1e-6), end - start):
                continue
            if f.count > 1 and held < f.duration:
                f = replace(f, count=max(1, int(round(f.count * held / f.duration))))
            inside.append(f)
        return replace(self, findings=tuple(inside))

    def timeline(self, min_segment: float = MIN_SEGMENT) -> list[tuple[float, float, str]]:
        """[(start, end, sentence), ...] covering the take: cut where the most salient
        finding changes, segments under ``min_segment`` s merged into a neighbour."""
        # timeline resolution, cells a second: ten, fewer for a take so long (or a frame
        # time so absurd) that ten would not fit in memory
        rate = min(10.0, TIMELINE_CELLS / max(self.duration, 1e-9))
        n = max(1, int(np.ceil(self.duration * rate)))
        best = np.full(n, -1)
        score = np.zeros(n)
        ranked = self.ranked()
        # walking forward and stepping sideways are two parts of a timeline
        labels = [ACTION[f.label] + ("" if f.kind != "locomotion" else
                                     f" {f.detail.get('direction', '')}") for f in ranked]
        for i, f in enumerate(ranked):
            # a jump's or a kick's span is its flight or swing; the take-off and the landing
            # around it belong to it too
            pad = EVENT_PAD if f.label in EVENTS else 0.0
            a = max(0, int((f.start - pad) * rate))
            b = max(a + 1, int(np.ceil((f.end + pad) * rate)))
            s = salience(f)
            sl = slice(a, min(b, n))
            better = score[sl] < s
            best[sl][better] = i
            score[sl][better] = s
        _give_gaps_to_events(best, [f.label in EVENTS for f in ranked],
                             int(round(GAP_REACH * rate)))
        # cells of the same coarse action belong together
        key = np.array([labels[i] if i >= 0 else "" for i in best], dtype=object)
        cuts = [0] + [i for i in range(1, n) if key[i] != key[i - 1]] + [n]
        segs = [[cuts[i], cuts[i + 1]] for i in range(len(cuts) - 1)]
        short = max(1, int(round(min_segment * rate)))
        merged = True
        while merged and len(segs) > 1:
            merged = False
            for j, (a, b) in enumerate(segs):
                if b - a < short:
                    k = j - 1 if j == len(segs) - 1 or (
                        j > 0 and segs[j - 1][1] - segs[j - 1][0] >= segs[j + 1][1] -
                        segs[j + 1][0]) else j + 1
                    lo, hi = min(j, k), max(j, k)
                    segs[lo:hi + 1] = [[segs[lo][0], segs[hi][1]]]
                    merged = True
                    break
        out = []
        for a, b in segs:
            t0, t1 = a / rate, min(self.duration, b / rate)
            # a segment is cut where the main action changes: its sentence says that one
            out.append((round(t0, 2), round(t1, 2), self.within(t0, t1).sentence(clauses=1)))
        # neighbours that say the same are one segment
        joined: list[tuple[float, float, str]] = []
        for seg in out:
            if joined and joined[-1][2] == seg[2]:
                joined[-1] = (joined[-1][0], seg[1], seg[2])
            else:
                joined.append(seg)
        return joined


def _give_gaps_to_events(best: np.ndarray, event: list[bool], reach: int) -> None:
    """In place: each run of cells no finding names (-1 in ``best``, (n,) indices into the
    ranked findings), at most ``reach`` cells long, that an event borders on one side and no
    event on the other, to that event; one between two events, split between them."""
    n = len(best)
    i = 0
    while i < n:
        if best[i] >= 0:
            i += 1
            continue
        j = i
        while j < n and best[j] < 0:
            j += 1
        left = int(best[i - 1]) if i > 0 else -1
        right = int(best[j]) if j < n else -1
        at_left, at_right = left >= 0 and event[left], right >= 0 and event[right]
        if j - i <= reach and (at_left or at_right):
            mid = (i + j) // 2 if at_left and at_right else (j if at_left else i)
            best[i:mid] = left
            best[mid:j] = right
        i = j


def analyse_positions(p21, fps: float) -> Analysis:
    """(T, 21, 3) Y-up positions (any unit) at ``fps`` -> :class:`Analysis`.

    A take with splices (``body.pieces``: recordings end to end, a capture glitch) is read
    piece by piece, each on its own floor and facing, so that nothing is found across a
    jump in the data that no body made.

    Raises:
        MotionlangError: positions of the wrong shape, not finite, one frame, no body.
    """
    spans = pieces(p21, fps)
    if len(spans) == 1:
        body = Body.from_positions(p21, fps)
        return Analysis(findings=tuple(_findings(body)), duration=body.duration,
                        leg=body.leg, stature=body.stature)
    p = np.asarray(p21)
    found: list[Finding] = []
    bodies = []
    for a, b in spans:
        body = Body.from_positions(p[a:b], fps)
        found += [f.shifted(a / fps) for f in _findings(body)]
        bodies.append(body)
    longest = max(bodies, key=lambda b: b.n)
    return Analysis(findings=tuple(sorted(found, key=lambda f: (f.start, f.label))),
                    duration=len(p) / fps, leg=longest.leg, stature=longest.stature)


def _findings(body: Body) -> list[Finding]:
    """Every detector's findings on ``body``, pruned, in time order."""
    found: list[Finding] = []
    found += _series_of_squats(postures(body))
    found += travel(body)
    found += in_place(body)
    found += jumps(body)
    found += turns(body)
    found += levels(body)
    found += limb_actions(body)
    kept = prune(found)
    # a dance is read from what the others found, and says the movements it is made of
    kept = said_by_dance(kept + dances(body, kept))
    return sorted(kept + _get_ups(kept, body.duration), key=lambda f: (f.start, f.label))

"""Which actions of a sentence a motion shows: the open-world check of generated (or any)
motion (``motionlang check "a person sits down" motion.bvh``).

The sentence's actions are read by ``analysis.words``; each is looked for among the
analysis' findings (or those that answer for it: a hop is a jump, a squat a crouch). An action
the analysis has no detector for is "cannot tell", never "no".
"""
from __future__ import annotations

import json
from dataclasses import dataclass

from motionlang.analysis.analyse import ACTION, Analysis
from motionlang.analysis.evidence import Finding
from motionlang.analysis.words import COMPATIBLE, mentions
from motionlang.errors import MotionlangError

#: the coarse actions some detector can find (others are "cannot tell")
DETECTABLE = frozenset(ACTION.values())


@dataclass(frozen=True)
class ActionCheck:
    """One action of a sentence against a motion.

    Attributes:
        action: the coarse action the sentence names (``analysis.words.ACTION_WORDS``).
        shown: True (seen as the sentence says it: on its side, in its direction for a
            walk or run, not all over before the action named before it where it says
            "then"), False (a detector for it exists and saw nothing so) or None (no
            detector: the analysis cannot tell).
        findings: the findings that show it, most confident first.
        negated: the sentence says the body does not do it ("does not jump").
        note: where ``shown`` is False though the action was seen: how it was seen
            otherwise ("on the right side, 0.9-2.9 s", "forward, 3.0-6.0 s", "only before
            the walk, 0.0-0.5 s").
    """

    action: str
    shown: bool | None
    findings: tuple[Finding, ...] = ()
    negated: bool = False
    note: str = ""

    @property
    def met(self) -> bool | None:
        """Whether the motion does what the sentence says of this action (shows it, or,
        where the sentence says not, does not); None where the analysis cannot tell."""
        return None if self.shown is None else self.shown != self.negated

    def line(self) -> str:
        """``sit: yes (1.9-4.1 s, confidence 0.97)`` / ``sit: no`` / ``throw: cannot tell``;
        ``jump (the sentence says not): yes (...)``; ``kick: no (seen on the right side,
        0.9-2.9 s)``."""
        name = f"{self.action} (the sentence says not)" if self.negated else self.action
        if self.shown is None:
            return f"{name}: cannot tell (no detector for it)"
        if not self.shown:
            return f"{name}: no" + (f" (seen {self.note})" if self.note else "")
        f = self.findings[0]
        return (f"{name}: yes ({f.start:.1f}-{f.end:.1f} s, {f.measure} {f.value:.2f}, "
                f"confidence {f.confidence:.2f})")

    def as_dict(self) -> dict:
        return {"action": self.action, "shown": self.shown, "negated": self.negated,
                "met": self.met, "note": self.note,
                "findings": [f.as_dict() for f in self.findings]}


#: actions of the hands, of which "both" says something
_HANDS = frozenset({"raise", "wave", "punch", "reach"})
#: how each direction a sentence says is seen in a walk's or a run's ``direction``
_DIRECTION_SEEN = {"forward": ("forward",), "backwards": ("backwards",),
                   "sideways": ("left", "right"), "in place": ()}


def _answers(action: str, f: Finding, *, exact: bool = False) -> bool:
    """Whether the finding ``f`` shows ``action`` (or, unless ``exact``, one that answers
    for it)."""
    accept = {action} if exact else {action, *COMPATIBLE.get(action, ())}
    return (ACTION[f.label] in accept or (
        action == "turn" and f.label in ("walk", "run") and
        f.detail.get("path", "straight") != "straight") or (   # a walk that turns
        # a dance says the kicks and spins it is made of
        f.label == "dance" and bool({ACTION[m] for m in f.detail.get("moves", ())} & accept)))


def _on_side(f: Finding, side: str) -> bool:
    """Whether ``f`` is on ``side`` ("left", "right", "both"): a finding of both sides
    answers for either, one of no side for any, a walk that turns by the way its path
    curves."""
    if f.label in ("walk", "run") and f.detail.get("path", "straight") != "straight":
        return side in str(f.detail["path"]) or f.detail["path"] == "in a circle"
    return f.side in (None, side, "both") if side != "both" else f.side in (None, "both")


def _went(f: Finding, direction: str) -> bool:
    if f.detail.get("in_place") or direction == "in place":
        # a walk in place goes nowhere (not forward, not backwards); one that goes is none
        return bool(f.detail.get("in_place")) == (direction == "in place")
    seen = f.detail.get("direction")
    return seen is None or seen in _DIRECTION_SEEN[direction]


#: Froude number that parts a slow walk from a quick one: the middle of an ordinary walk's
#: (``locomotion.WALK_SLOW`` .. ``WALK_BRISK``)
PACE_SPLIT = 0.2


def _paced(f: Finding, pace: str) -> bool:
    """Whether a walk is at ``pace`` ("slow", "fast"), by its Froude number (a walk without
    one answers either)."""
    fr = f.detail.get("froude")
    if fr is None:
        return True
    return fr < PACE_SPLIT if pace == "slow" else fr >= PACE_SPLIT


def _how(f: Finding) -> str:
    """A finding's side or direction and its span, for a note: "on the right side, 0.9-2.9
    s", "backwards, 0.0-3.0 s"."""
    if f.detail.get("in_place"):
        return f"in place, {f.start:.1f}-{f.end:.1f} s"
    if f.label in ("walk", "run", "jump") and f.detail.get("direction"):
        how = " ".join([f.detail["direction"]] + ([f.detail["speed"]] if f.detail.get("speed")
                                                   else []))
        if f.detail.get("path") not in (None, "straight"):
            how += f" {f.detail['path']}"
        if f.label == "walk" and f.detail.get("froude") is not None and not f.detail.get("speed"):
            how += ", slower than most walks" if f.detail["froude"] < PACE_SPLIT else \
                ", quicker than most walks"
        return f"{how}, {f.start:.1f}-{f.end:.1f} s"
    return f"on the {f.side} side, {f.start:.1f}-{f.end:.1f} s" if f.side else \
        f"{f.start:.1f}-{f.end:.1f} s"


def check_sentence(text: str, analysis: Analysis) -> list[ActionCheck]:
    """Every action ``text`` names, in its order, against ``analysis``: seen at all, then on
    the side the sentence gives it ("both" asked of the hands only) and, for a walk or a
    run, in its direction, not all over before the action
    named before it began where the sentence says "then" (``analysis.words.mentions``);
    an action it says the body does not do is looked for by its own findings only.

    Raises:
        MotionlangError: an empty sentence.
    """
    if not text.strip():
        raise MotionlangError("the sentence to check is empty")
    out: list[ActionCheck] = []
    previous: tuple[str, float] | None = None   # the action named before, where it began
    for m in mentions(text):
        if m.action not in DETECTABLE and not COMPATIBLE.get(m.action, set()) & DETECTABLE:
            out.append(ActionCheck(m.action, None, negated=m.negated))
            previous = None
            continue
        # "does not wave" asks that no wave be seen, not that no hand be up
        seen = sorted((f for f in analysis.findings
                       if _answers(m.action, f, exact=m.negated)), key=lambda f: -f.confidence)
        hits, note = seen, ""
        # "both" asked of the hands only ("jumps with both feet" says no more than a jump)
        if m.side in ("left", "right") or m.side == "both" and m.action in _HANDS:
            hits = [f for f in hits if _on_side(f, m.side)]
        # a jump's direction is only up, down or away (no side, no back): not asked of it
        if m.direction is not None and m.action in ("walk", "run"):
            hits = [f for f in hits if _went(f, m.direction)]
        if m.path is not None and m.action in ("walk", "run"):
            hits = [f for f in hits if f.detail.get("path") == m.path]
        if m.pace is not None and m.action == "walk":
            hits = [f for f in hits if _paced(f, m.pace)]
        if seen and not hits:
            note = _how(seen[0])
        if m.after_previous and previous is not None and hits:
            # "then": not all over before the action named before it began (a turn made
            # while walking, a wave within a raise, a walk after a jump all are)
            later = [f for f in hits if f.end > previous[1]]
            if not later:
                note = f"only before the {previous[0]}, {hits[0].start:.1f}-{hits[0].end:.1f} s"
            hits = later
        out.append(ActionCheck(m.action, bool(hits), tuple(hits), m.negated, note))
        first = min((f.start for f in hits), default=None)
        previous = (m.action, first) if first is not None and not m.negated else None
    return out


def unmet(text: str, analysis: Analysis) -> list[str]:
    """The actions of ``text`` the motion of ``analysis`` does not do as the sentence says
    (:attr:`ActionCheck.met` False), in the sentence's order; [] for a sentence that names
    none (an empty one too)."""
    if not text.strip():
        return []
    return [c.action for c in check_sentence(text, analysis) if c.met is False]


def not_shown_line(missed: list[str]) -> str:
    """The line that says a motion made for a sentence misses ``missed``."""
    return (f"the motion made does not show {', '.join(missed)} as the sentence asks "
            "(motionlang check says why)")


def printed(text: str, checks: list[ActionCheck], *, as_json: bool = False) -> str:
    """What ``motionlang check`` prints: a line per action (:meth:`ActionCheck.line`), or
    the JSON list of :meth:`ActionCheck.as_dict`."""
    if as_json:
        return json.dumps([c.as_dict() for c in checks], indent=1)
    if not checks:
        return f"the sentence names no action motionlang can read: {text!r}"
    return "\n".join(c.line() for c in checks)


#: path and direction words of a caption, and what a travel finding must show for them
_MANNER = {"circle": ("path", "in a circle"), "circles": ("path", "in a circle"),
           "backwards": ("direction", "backwards"), "backward": ("direction", "backwards"),
           "sideways": ("direction", ("left", "right"))}


def contradicted(text: str, analysis: Analysis) -> bool:
    """Whether ``text`` says how the body travels ("in a circle", "backwards", "sideways")
    where the analysis saw it travel otherwise; False where it saw no travel at all."""
    travel = [f for f in analysis.findings if f.label in ("walk", "run")]
    if not travel:
        return False
    for word in text.lower().replace(",", " ").split():
        if word in _MANNER:
            key, want = _MANNER[word]
            allowed = want if isinstance(want, tuple) else (want,)
            if not any(f.detail.get(key) in allowed for f in travel):
                return True
    return False

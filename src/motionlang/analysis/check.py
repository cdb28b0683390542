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
from motionlang.analysis.words import COMPATIBLE, actions_named
from motionlang.errors import MotionlangError

#: the coarse actions some detector can find (others are "cannot tell")
DETECTABLE = frozenset(ACTION.values())


@dataclass(frozen=True)
class ActionCheck:
    """One action of a sentence against a motion.

    Attributes:
        action: the coarse action the sentence names (``analysis.words.ACTION_WORDS``).
        shown: True (seen), False (a detector for it exists and saw nothing) or None
            (no detector: the analysis cannot tell).
        findings: the findings that show it, most confident first.
    """

    action: str
    shown: bool | None
    findings: tuple[Finding, ...] = ()

    def line(self) -> str:
        """``sit: yes (1.9-4.1 s, confidence 0.97)`` / ``sit: no`` / ``throw: cannot tell``."""
        if self.shown is None:
            return f"{self.action}: cannot tell (no detector for it)"
        if not self.shown:
            return f"{self.action}: no"
        f = self.findings[0]
        return (f"{self.action}: yes ({f.start:.1f}-{f.end:.1f} s, {f.measure} {f.value:.2f}, "
                f"confidence {f.confidence:.2f})")

    def as_dict(self) -> dict:
        return {"action": self.action, "shown": self.shown,
                "findings": [f.as_dict() for f in self.findings]}


def check_sentence(text: str, analysis: Analysis) -> list[ActionCheck]:
    """Every action ``text`` names, in its order, against ``analysis``.

    Raises:
        MotionlangError: an empty sentence.
    """
    if not text.strip():
        raise MotionlangError("the sentence to check is empty")
    out = []
    for action in actions_named(text):
        if action not in DETECTABLE and not COMPATIBLE.get(action, set()) & DETECTABLE:
            out.append(ActionCheck(action, None))
            continue
        accept = {action, *COMPATIBLE.get(action, ())}
        hits = sorted((f for f in analysis.findings if ACTION[f.label] in accept or (
            action == "turn" and f.label in ("walk", "run") and
            f.detail.get("path", "straight") != "straight") or (   # a walk that turns
            # a dance says the kicks and spins it is made of
            f.label == "dance" and {ACTION[m] for m in f.detail.get("moves", ())} & accept)),
                      key=lambda f: -f.confidence)
        out.append(ActionCheck(action, bool(hits), tuple(hits)))
    return out


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


#: findings of a hand held up, which the wave detector looked at for a wave
_ARM_UP = ("raise", "reach")


def contradicted(text: str, analysis: Analysis) -> bool:
    """Whether ``text`` says how the body travels ("in a circle", "backwards", "sideways")
    where the analysis saw it travel otherwise (False where it saw no travel at all), or
    says it waves where the analysis saw a hand held up and no wave: the hand was up, and
    it did not swing (a raise answers for a wave in :func:`check_sentence`, where a wave too
    small to see must not be called absent; here the sentence is weighed against what was
    seen)."""
    labels = {f.label for f in analysis.findings} | {
        m for f in analysis.findings if f.label == "dance" for m in f.detail.get("moves", ())}
    if "wave" in actions_named(text) and "wave" not in labels and labels & set(_ARM_UP):
        return True
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

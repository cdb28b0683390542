"""What the analysis saw in each take of an index, and a query's actions matched against it.

When a take is indexed it is also analysed once (:mod:`motionlang.analysis`: physics and
geometry, no model) and its findings are stored beside its vectors, compact: label, span in
seconds, confidence, side and count. A query's actions are read by the same reader that
``describe``, ``check`` and ``generate`` use (``analysis.words``). A take that shows an
action the query asks for is a hit because the body does it, whatever the learned encoder
makes of the sentence: this is how a library answers "someone sits down" for actions its
model never saw. Each such hit says why (``sits: 12.4-15.0 s``).

Matching is strict: a finding answers for the action its label names (``analysis.ACTION``:
a hop is a jump, a squat a crouch), never for a merely compatible one (a jump is no climb);
the widenings are :data:`ALSO` (stepping up onto something is climbing up) and a dance,
which answers for the movements it is made of (a ballet take's battements are kicks), after
the takes that show them on their own (:data:`IN_A_DANCE`).
"""
from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from typing import Any

from motionlang.analysis import ACTION, analyse
from motionlang.analysis.words import actions_named
from motionlang.errors import MotionlangError
from motionlang.kinematics.motion import Motion

#: the stored fields of a finding, in this order (a dance also stores its ``moves``)
FIELDS = ("label", "start", "end", "confidence", "side", "count")
#: findings of a take this close (s) or closer are one hit: a walk and the sitting down
#: right after it, or kicks of one series
JOIN_GAP = 2.0
#: seconds shown around a matched finding (a kick's span is its swing alone)
PAD = 0.5
#: the actions some detector finds
DETECTABLE = frozenset(ACTION.values())
#: labels that answer for an action besides its own
ALSO = {"climb": ("step_up",)}
#: a dance answers for one of its movements with its confidence times this (search ranks
#: a take whose own finding shows the action before a dance that has it among its moves)
IN_A_DANCE = 0.5


def answers(label: str, action: str) -> bool:
    """Whether a finding labelled ``label`` shows ``action``."""
    return ACTION[label] == action or label in ALSO.get(action, ())


def in_a_dance(finding: dict, action: str) -> bool:
    """Whether a stored dance finding has ``action`` among its movements."""
    return finding["label"] == "dance" and any(
        m in ACTION and answers(m, action) for m in finding.get("moves", ()))


def compact(finding: Any) -> dict:
    """An ``analysis.Finding`` as the index stores it (:data:`FIELDS`, rounded)."""
    out = {"label": finding.label, "start": round(float(finding.start), 2),
           "end": round(float(finding.end), 2),
           "confidence": round(float(finding.confidence), 3), "side": finding.side,
           "count": int(finding.count)}
    if finding.label == "dance":
        out["moves"] = list(finding.detail.get("moves", ()))
    return out


def take_findings(motion: Motion) -> list[dict]:
    """The compact findings of one take (:func:`compact`), in time order; ``[]`` where the
    analysis cannot read the body (one frame, all joints at one point): the take stays
    searchable by its vectors."""
    try:
        found = analyse(motion, joint_map=motion.meta.get("joint_map")).findings
    except MotionlangError:
        return []
    return [compact(f) for f in found]


def valid_findings(value: Any) -> bool:
    """Whether ``value`` is a list of stored findings (what a reader of an index checks)."""
    if not isinstance(value, list):
        return False
    for f in value:
        if not isinstance(f, dict) or not _is_label(f.get("label")):
            return False
        nums = [f.get(k) for k in ("start", "end", "confidence", "count")]
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) and
                   math.isfinite(x) for x in nums) or f["end"] < f["start"]:
            return False
        moves = f.get("moves", [])
        if not isinstance(moves, list) or not all(_is_label(m) for m in moves):
            return False
    return True


def _is_label(value: Any) -> bool:
    return isinstance(value, str) and value in ACTION


def query_actions(text: str) -> list[str]:
    """The actions ``text`` names that some detector can find, in its order."""
    return [a for a in actions_named(text) if a in DETECTABLE]


def where_actions(text: str) -> list[str]:
    """The actions of a ``--where`` filter.

    Raises:
        MotionlangError: it names no action the analysis finds.
    """
    actions = query_actions(text)
    if not actions:
        raise MotionlangError(f"--where {text!r} names no action the analysis finds (one of "
                              f"{', '.join(sorted(DETECTABLE - {'arms_out'}))})")
    return actions


#: labels whose reason is not their action's verb
LABEL_WORDS = {"all_fours": "on all fours", "one_leg": "balances on one leg",
               "hang": "hangs", "step_up": "steps up", "step_down": "steps down",
               "squat": "squats", "hop": "hops", "touch_floor": "touches the floor",
               "get_up": "gets up", "arms_out": "holds the arms out"}


def verb(action: str) -> str:
    """``sit`` -> ``sits``, ``crouch`` -> ``crouches`` (how a reason names it)."""
    return action + ("es" if action.endswith(("ch", "sh", "s", "x")) else "s")


def reason(label: str) -> str:
    """How a hit's reason names a finding: ``sits``, ``on all fours``, ``hops``."""
    return LABEL_WORDS.get(label) or verb(ACTION[label])


@dataclass(frozen=True)
class Match:
    """Findings of one take that show actions a query asks for, close enough to be one hit.

    Attributes:
        start, end: the hit's span, seconds (the findings' span, :data:`PAD` around it,
            within the take).
        actions: the query's actions shown, in the query's order.
        confidence: mean over those actions of their best finding's confidence.
        why: ``"sits: 12.4-15.0 s"``, one part per finding.
        shows: the findings' own span, seconds (``start``, ``end`` without the pad).
        direct: how many of ``actions`` a finding of their own shows (not only a dance
            they are among the moves of): search ranks those hits first.
    """

    start: float
    end: float
    actions: tuple[str, ...]
    confidence: float
    why: str
    shows: tuple[float, float] = (0.0, 0.0)
    direct: int = 0


def matches(findings: list[dict], actions: list[str], duration: float, *,
            min_duration: float = 0.0) -> list[Match]:
    """The hits a take's stored findings give for ``actions``: its findings of those
    actions (each at least ``min_duration`` s long; a dance for the movements it is made
    of, :data:`IN_A_DANCE`), those within :data:`JOIN_GAP` s of one another taken together,
    in time order."""
    def direct(f: dict, a: str) -> bool:
        return answers(f["label"], a)

    def shows(f: dict, a: str) -> bool:
        return direct(f, a) or in_a_dance(f, a)

    wanted = [f for f in findings if any(shows(f, a) for a in actions) and
              f["end"] - f["start"] >= min_duration]
    wanted.sort(key=lambda f: f["start"])
    groups: list[list[dict]] = []
    for f in wanted:
        if groups and f["start"] <= max(g["end"] for g in groups[-1]) + JOIN_GAP:
            groups[-1].append(f)
        else:
            groups.append([f])
    out = []
    for g in groups:
        shown = [a for a in actions if any(shows(f, a) for f in g)]
        best = [max(f["confidence"] * (1.0 if direct(f, a) else IN_A_DANCE)
                    for f in g if shows(f, a)) for a in shown]
        why = "; ".join(f"{_why(f, actions)}: {f['start']:.1f}-{f['end']:.1f} s" for f in g)
        lo, hi = min(f["start"] for f in g), max(f["end"] for f in g)
        own = sum(any(direct(f, a) for f in g) for a in shown)
        out.append(Match(max(0.0, lo - PAD), min(duration, hi + PAD), tuple(shown),
                         sum(best) / len(best), why, (lo, hi), own))
    return out


def _why(f: dict, actions: list[str]) -> str:
    """How a hit's reason names one finding: ``kicks``, or a dance that answers for its
    movements as ``dances (kicks among its moves)``."""
    inside = [a for a in actions if not answers(f["label"], a) and in_a_dance(f, a)]
    if inside:
        return f"{reason(f['label'])} ({', '.join(verb(a) for a in inside)} among its moves)"
    return reason(f["label"])


def path_allowed(path: str, glob: str | None) -> bool:
    """Whether a take's path (relative to the indexed folder) passes ``--path-glob``."""
    return glob is None or fnmatch.fnmatchcase(path, glob)

"""Recover primitive parameters (action, side, count, direction, speed, angle) from English.

Used to score generated descriptions against ground truth: a rule-based reader of the
KIT-style sentences that the grammar writes and of the common hand-written variants
("someone slowly takes 4 steps backwards", "a person waves twice with his left hand").

Method: the sentence is cut into clauses at connectives ("then", "and", "while", commas);
each clause holds one action, found from its verb or noun, and the parameter words in the
clause are attached to it. A clause without an action word extends the previous one.
"X while Y" makes the upper-body action an overlay (``layer="upper"``) listed after the
body action it rides on.
"""
from __future__ import annotations

import re

from motionlang.datasets.synth.spec import UPPER_ACTIONS, Primitive

_NUMBERS = {w: i for i, w in enumerate(
    ("zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen "
     "fifteen sixteen seventeen eighteen nineteen twenty").split())}
_NUMBERS.update({"a": 1, "an": 1, "single": 1, "a couple of": 2, "couple": 2})

# word -> action; checked on whole tokens (after normalisation)
_ACTION_WORDS = {
    "walk": "walk walks walking walked steps step takes taking sidesteps sidestepping "
            "sidestep strolls strolling goes going moves moving",
    "run": "run runs running jog jogs jogging sprints sprinting",
    "turn": "turn turns turning rotates rotating",
    "wave": "wave waves waving",
    "kick": "kick kicks kicking",
    "stomp": "stomp stomps stomping stamps stamping",
    "squat": "squat squats squatting",
    "jump": "jump jumps jumping hop hops hopping",
    "raise_arms": "raise raises raising lift lifts lifting",
    "bow": "bow bows bowing",
    "wipe": "wipe wipes wiping wiped cleans cleaning",
    "punch": "punch punches punching boxes boxing",
    "stand": "stand stands standing stays staying waits waiting still",
}
_ACTION = {w: a for a, ws in _ACTION_WORDS.items() for w in ws.split()}
# generic verbs that take the action from a noun later in the clause ("performs a squat")
_LIGHT = {"performs", "performing", "does", "doing", "makes", "making", "throws", "throwing",
          "takes", "taking"}
_NOUN_ACTION = {"squat": "squat", "squats": "squat", "jump": "jump", "jumps": "jump",
                "punch": "punch", "punches": "punch", "kick": "kick", "kicks": "kick",
                "bow": "bow", "bows": "bow", "turn": "turn", "wave": "wave",
                "steps": "walk", "step": "walk", "wiping": "wipe", "waving": "wave",
                "punching": "punch", "kicking": "kick"}
_COUNT_UNITS = {"steps", "step", "times", "time", "squats", "squat", "jumps", "jump",
                "punches", "punch", "kicks", "kick", "bows", "bow", "waves", "wave", "strides",
                "hops", "hop"}
_SPEED = {"slowly": "slow", "slow": "slow", "leisurely": "slow",
          "quickly": "fast", "fast": "fast", "rapidly": "fast", "briskly": "fast",
          "quick": "fast", "hastily": "fast",
          "normal": "normal", "medium": "normal", "moderate": "normal", "average": "normal"}
_SPLIT = re.compile(r"\s*(?:,|;|\.|\bafter that\b|\bafterwards\b|\band then\b|\bthen\b|"
                    r"\band\b|\bwhile\b|\bbefore\b|\bfirst\b)\s*")


def _normalise(text: str) -> str:
    t = text.lower()
    t = t.replace("counter-clockwise", "counterclockwise").replace("counter clockwise",
                                                                   "counterclockwise")
    t = t.replace("anti-clockwise", "counterclockwise").replace("anticlockwise",
                                                                "counterclockwise")
    t = re.sub(r"(\d+)\s*-?\s*degrees?", r"\1 degrees", t)
    t = t.replace("-", " ")  # "left-turn", "spot-turn", "u-turn"
    t = t.replace("a couple of", "two")
    t = re.sub(r"[^a-z0-9,;.\- ]", " ", t)
    return t


def _clauses(text: str) -> list[tuple[str, bool]]:
    """Split into (clause, follows_while) pairs."""
    out = []
    pos = 0
    follows_while = False
    for m in _SPLIT.finditer(text):
        out.append((text[pos:m.start()].strip(), follows_while))
        follows_while = "while" in m.group(0)
        pos = m.end()
    out.append((text[pos:].strip(), follows_while))
    return [(c, w) for c, w in out if c]


def _number(tok: str) -> int | None:
    if tok.isdigit():
        return int(tok)
    return _NUMBERS.get(tok)


#: tokens that name an action but cannot start a second one inside a clause
#: ("walks four steps" is one action, "stands still" too)
_NOT_STARTERS = {"steps", "step", "still"}


def _find_action(toks: list[str], start: int = 0) -> tuple[str | None, int, int]:
    """The first action at or after ``start``: (action, first token, last head token).

    A light verb ("performs", "takes") defers to the action noun after it ("a squat"),
    and the head then ends at that noun. Returns (None, -1, -1) if there is none.
    """
    for i in range(start, len(toks)):
        t = toks[i]
        if t in _LIGHT:
            for j in range(i + 1, len(toks)):
                if toks[j] in _NOUN_ACTION:
                    return _NOUN_ACTION[toks[j]], i, j
            if t in ("takes", "taking"):
                continue
        if t in _NOT_STARTERS and (i > 0 or start > 0):
            continue
        if t in ("goes", "going", "moves", "moving") and any(
                w in toks for w in ("squat", "down", "knees")):
            continue
        if t in _ACTION:
            a = _ACTION[t]
            if a == "stand" and t in ("stand", "stands", "standing") and "up" in toks[i + 1:i + 2]:
                continue  # "stands up" ends a squat, it is not "stands still"
            return a, i, i
    return None, -1, -1


def _split_actions(toks: list[str]) -> list[tuple[str, list[str]]]:
    """Cut a clause at each further action ("walks forward takes a turn" is two)."""
    found = []
    start = 0
    while True:
        a, i, head = _find_action(toks, start)
        if a is None:
            break
        found.append((a, i))
        start = head + 1
    cuts = [0] + [i for _, i in found[1:]] + [len(toks)]
    return [(a, toks[cuts[k]:cuts[k + 1]]) for k, (a, _) in enumerate(found)]


def _attributes(prim: Primitive, toks: list[str]) -> None:
    """Fill side/count/direction/speed/angle of ``prim`` from the clause's tokens."""
    text = " ".join(toks)
    a = prim.action
    for i, t in enumerate(toks):
        nxt = toks[i + 1] if i + 1 < len(toks) else ""
        nxt2 = toks[i + 2] if i + 2 < len(toks) else ""
        if t in ("left", "right", "both"):
            prim.side = t
        elif t in ("leftwards", "leftward", "rightwards", "rightward"):
            prim.side = "left" if t.startswith("left") else "right"
        elif t in ("clockwise", "counterclockwise") and a in ("turn", "walk", "run"):
            prim.side = "right" if t == "clockwise" else "left"
            if a != "turn":
                prim.direction = "circle"
        elif t in ("arms", "hands", "feet", "legs", "fists") and a in UPPER_ACTIONS + (
                "kick", "stomp") and prim.side is None and "left" not in toks \
                and "right" not in toks:
            prim.side = "both"
        elif t in ("once",):
            prim.count = 1
        elif t == "twice":
            prim.count = 2
        elif t == "thrice":
            prim.count = 3
        elif _number(t) is not None and t not in ("a", "an") and nxt.startswith("degree"):
            prim.angle = _number(t)
        elif _number(t) is not None and (nxt in _COUNT_UNITS or nxt2 in _COUNT_UNITS and
                                         nxt in ("more", "small", "big", "quick", "slow")):
            prim.count = _number(t)
        elif t in ("quarter",):
            prim.angle = 90
        elif t == "half" and a == "turn":
            prim.angle = 180
        elif t in ("around", "round") and a == "turn":
            prim.angle = 180
        elif t in _SPEED and not (t in ("normal", "medium", "average", "moderate") and
                                  nxt not in ("pace", "speed", "tempo")):
            prim.speed = _SPEED[t]
    if a in ("walk", "run"):
        if "circle" in toks or "circles" in toks:
            prim.direction = "circle"
        elif re.search(r"\bbackwards?\b", text):  # "walks back" is returning, not a direction
            prim.direction = "backward"
        elif re.search(r"\b(forwards?|ahead|straight)\b", text):
            prim.direction = "forward"
        elif re.search(r"\b(leftwards|rightwards|sideways|sidesteps?|sidestepping)\b", text) \
                or re.search(r"\bto (the|his|her|their|its) (left|right)\b", text):
            if prim.side in ("left", "right"):
                prim.direction = prim.side
        if prim.direction != "circle":
            # sideways walking: the direction is the side; otherwise a side word is about
            # the leading foot ("starting with the left foot"), not a parameter
            prim.side = None
    elif a == "jump":
        if re.search(r"\b(forwards?|ahead)\b", text):
            prim.direction = "forward"
        elif re.search(r"\b(in place|on the spot|on the spot|up and down|on the same spot)\b",
                       text):
            prim.direction = "in_place"


def extract(sentence: str) -> list[Primitive]:
    """Parameters stated in ``sentence``, as primitives in the grammar's order.

    Body primitives come in time order; an upper-body action joined by "while" follows the
    body primitive it overlays, with ``layer="upper"``. Unstated parameters are None.
    """
    text = _normalise(sentence)
    prims: list[tuple[Primitive, bool]] = []
    for clause, follows_while in _clauses(text):
        toks = clause.split()
        parts = _split_actions(toks)
        if not parts:
            if prims:  # a dangling attribute phrase ("..., with the left hand")
                _attributes(prims[-1][0], toks)
            continue
        for k, (action, part) in enumerate(parts):
            p = Primitive(action)
            _attributes(p, part)
            prims.append((p, follows_while and k == 0))
    out: list[Primitive] = []
    i = 0
    while i < len(prims):
        p, _ = prims[i]
        if i + 1 < len(prims) and prims[i + 1][1]:
            q = prims[i + 1][0]
            body, upper = (q, p) if p.action in UPPER_ACTIONS and q.action not in \
                UPPER_ACTIONS else (p, q)
            upper.layer = "upper"
            out.extend([body, upper])
            i += 2
            continue
        out.append(p)
        i += 1
    return out


def extract_keys(sentence: str) -> list[tuple]:
    """``[p.key() for p in extract(sentence)]`` — convenient for scoring."""
    return [p.key() for p in extract(sentence)]


def score(text: str, truth: list[Primitive]) -> dict:
    """Score a (generated) description against ground-truth primitives.

    Extracted primitives are matched to the truth in order, by action (a greedy
    in-order alignment). For each parameter the description states, it is right or wrong.

    Returns:
        {"actions_match": the action sequences are identical,
         "matched": number of aligned primitives,
         field: (correct, stated) for side, count, direction, speed and angle}.
    """
    got = extract(text)
    out: dict = {"actions_match": [p.action for p in got] == [p.action for p in truth]}
    fields = ("side", "count", "direction", "speed", "angle")
    tally = {f: [0, 0] for f in fields}
    j = matched = 0
    for p in got:
        while j < len(truth) and truth[j].action != p.action:
            j += 1
        if j == len(truth):
            break
        matched += 1
        for f in fields:
            v = getattr(p, f)
            if v is not None:
                tally[f][1] += 1
                tally[f][0] += int(v == getattr(truth[j], f))
        j += 1
    out["matched"] = matched
    out.update({f: tuple(v) for f, v in tally.items()})
    return out

"""KIT-style English sentences for a list of primitives.

Each generated sentence comes with the parameters it actually states (a masked copy of the
ground truth), so the parameter extractor can be tested exactly: "a person walks forward"
states the action and direction but not the step count. Vocabulary follows the real KIT-ML
annotations (subjects "a person", "someone", "a human", "the subject"; "forward/forwards/
ahead"; numbers as words and digits; simple and progressive present).
"""
from __future__ import annotations

import numpy as np

from motionlang.datasets.synth.spec import LOCOMOTION, Primitive

NUMBER_WORDS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight",
                "nine", "ten", "eleven", "twelve", "thirteen", "fourteen", "fifteen",
                "sixteen", "seventeen", "eighteen", "nineteen", "twenty")
SUBJECTS = ("a person", "someone", "a human", "the subject", "the person", "a man",
            "somebody", "a woman")
POSSESSIVE = {"a person": ("his", "their", "the"), "someone": ("his", "their", "the"),
              "a human": ("his", "its", "the"), "the subject": ("his", "the"),
              "the person": ("his", "the"), "a man": ("his", "the"),
              "somebody": ("his", "the"), "a woman": ("her", "the")}

DIR_WORDS = {
    "forward": ("forward", "forwards", "ahead", "straight ahead", "straight forward"),
    "backward": ("backward", "backwards"),
    "left": ("to the left", "sideways to the left", "to the left side", "leftwards"),
    "right": ("to the right", "sideways to the right", "to the right side", "rightwards"),
}
CIRCLE_WORDS = {"left": ("in a circle to the left", "in a circle counterclockwise",
                         "counterclockwise in a circle", "around in a circle counterclockwise"),
                "right": ("in a circle to the right", "in a circle clockwise",
                          "clockwise in a circle")}
SPEED_WORDS = {"slow": ("slowly", "at a slow pace", "very slowly"),
               "normal": ("at a normal pace", "at normal speed", "at medium speed"),
               "fast": ("quickly", "fast", "at a fast pace", "briskly")}
VERBS = {  # action -> (3rd person, -ing) pairs
    "walk": (("walks", "walking"),), "run": (("runs", "running"), ("jogs", "jogging")),
    "turn": (("turns", "turning"),), "wave": (("waves", "waving"),),
    "kick": (("kicks", "kicking"),), "stomp": (("stomps", "stomping"),),
    "squat": (("squats", "squatting"),), "jump": (("jumps", "jumping"), ("hops", "hopping")),
    "raise_arms": (("raises", "raising"), ("lifts", "lifting")),
    "bow": (("bows", "bowing"),), "wipe": (("wipes", "wiping"),),
    "punch": (("punches", "punching"),),
    "stand": (("stands still", "standing still"), ("stands in place", "standing in place"),
              ("stays still", "staying still"), ("waits", "waiting")),
}
NOUNS = {"squat": "squat", "jump": "jump", "punch": "punch", "kick": "kick", "bow": "bow"}


def _pick(rng: np.random.Generator, seq):
    return seq[int(rng.integers(len(seq)))]


def number(n: int, rng: np.random.Generator) -> str:
    """``n`` as a word or as digits (KIT annotators use both)."""
    if n < len(NUMBER_WORDS) and rng.random() < 0.6:
        return NUMBER_WORDS[n]
    return str(n)


def times(n: int, rng: np.random.Generator) -> str:
    if n == 1:
        return "once" if rng.random() < 0.8 else _pick(rng, ("one time", "a single time"))
    if n == 2 and rng.random() < 0.5:
        return "twice"
    return f"{number(n, rng)} times"


def plural(noun: str, n: int) -> str:
    if n == 1:
        return noun
    return noun + ("es" if noun.endswith(("ch", "sh")) else "s")


class _Phrase:
    """Builds one verb phrase; records which parameters it stated."""

    def __init__(self, rng, prim: Primitive, ing: bool, poss: str):
        self.rng, self.p, self.ing, self.poss = rng, prim, ing, poss
        self.said: set[str] = set()

    def verb(self, pair) -> str:
        return pair[1] if self.ing else pair[0]

    def say(self, field: str, text: str) -> str:
        self.said.add(field)
        return text

    def maybe(self, prob: float) -> bool:
        return self.rng.random() < prob


def _side_part(ph: _Phrase, limb: str) -> str:
    """"with the right hand", "with both hands" (always states the side)."""
    side = ph.p.side
    if side == "both":
        return ph.say("side", f"with both {limb}s")
    return ph.say("side", f"with {ph.poss} {side} {limb}")


def _speed_part(ph: _Phrase, prob: float) -> str:
    if ph.p.speed is None or not ph.maybe(prob):
        return ""
    return ph.say("speed", _pick(ph.rng, SPEED_WORDS[ph.p.speed]))


def _locomotion(ph: _Phrase) -> str:
    p, rng = ph.p, ph.rng
    parts: list[str] = []
    if p.direction == "circle":
        direction = ph.say("direction", "")
        if ph.maybe(0.8):
            direction = ph.say("side", _pick(rng, CIRCLE_WORDS[p.side]))
        else:
            direction = "in a circle"
    else:
        direction = ph.say("direction", _pick(rng, DIR_WORDS[p.direction]))
    count = ""
    if p.count and p.direction != "circle" and ph.maybe(0.6):
        count = ph.say("count", f"{number(p.count, rng)} {plural('step', p.count)}")
    speed = _speed_part(ph, 0.5 if p.speed != "normal" else 0.25)
    if p.action == "walk" and count and ph.maybe(0.3):
        parts = [ph.verb(("takes", "taking")), count, direction]
    elif p.action == "walk" and p.direction in ("left", "right") and ph.maybe(0.4):
        parts = [ph.verb(("sidesteps", "sidestepping")), count, direction.replace("sideways ", "")]
    else:
        parts = [ph.verb(_pick(rng, VERBS[p.action])), count, direction]
    if speed:
        if speed.endswith("ly") and ph.maybe(0.3) and not ph.ing:
            parts.insert(0, speed)
        else:
            parts.append(speed)
    return " ".join(x for x in parts if x)


def _turn(ph: _Phrase) -> str:
    p, rng = ph.p, ph.rng
    side = ph.say("side", _pick(rng, (f"to the {p.side}", p.side, f"to {ph.poss} {p.side}",
                                       "clockwise" if p.side == "right" else "counterclockwise")))
    r = rng.random()
    if p.angle == 180 and r < 0.35:
        ph.say("angle", "")
        around = ph.verb(("turns around", "turning around"))
        if ph.maybe(0.6):
            side = f"to the {p.side}" if side in ("left", "right") else side
            return f"{around} {side}"
        ph.said.discard("side")
        return around
    if r < 0.6:
        deg = ph.say("angle", f"{number(p.angle, rng)} degrees")
        return f"{ph.verb(('turns', 'turning'))} {deg} {side}"
    if r < 0.75:
        kind = ph.say("angle", "quarter" if p.angle == 90 else "half")
        return f"{ph.verb(('makes', 'making'))} a {kind} turn {side}"
    return f"{ph.verb(('turns', 'turning'))} {side}"


def _limb_action(ph: _Phrase, limb: str) -> str:
    """wave / kick / stomp / punch / wipe: side always stated, count sometimes."""
    p, rng = ph.p, ph.rng
    cnt = ""
    if p.count and ph.maybe(0.6):
        cnt = ph.say("count", times(p.count, rng))
    if p.action in NOUNS and p.count and ph.maybe(0.3):
        noun = NOUNS[p.action]
        verb = ph.verb(_pick(rng, (("performs", "performing"), ("does", "doing"),
                                   ("throws", "throwing")) if p.action == "punch" else
                              (("performs", "performing"), ("does", "doing"))))
        n = ph.say("count", "a" if p.count == 1 else number(p.count, rng))
        return f"{verb} {n} {plural(noun, p.count)} {_side_part(ph, limb)}"
    if p.action == "wipe" and ph.maybe(0.5):
        return (f"{ph.verb(_pick(rng, (('wipes', 'wiping'), ('cleans', 'cleaning'))))} "
                f"{_pick(rng, ('a surface', 'the table', 'a table', 'the window'))} "
                f"{_side_part(ph, limb)} {cnt}").strip()
    parts = [ph.verb(_pick(rng, VERBS[p.action])), _side_part(ph, limb), cnt]
    if cnt and ph.maybe(0.5):
        parts = [parts[0], cnt, parts[1]]
    return " ".join(x for x in parts if x)


def _repeat_action(ph: _Phrase) -> str:
    """squat / bow / jump / raise_arms / stand."""
    p, rng = ph.p, ph.rng
    if p.action == "stand":
        return ph.verb(_pick(rng, VERBS["stand"]))
    extra = ""
    if p.action == "jump":
        extra = ph.say("direction", _pick(rng, ("forward", "forwards", "ahead"))
                       if p.direction == "forward" else
                       _pick(rng, ("in place", "on the spot", "on the spot", "in place")))
    if p.action == "raise_arms":
        if p.side == "both":
            arms = ph.say("side", _pick(rng, ("both arms", f"{ph.poss} arms", "both hands")))
        else:
            arms = ph.say("side", f"{ph.poss} {p.side} {_pick(rng, ('arm', 'hand'))}")
        cnt = ph.say("count", times(p.count, rng)) if p.count and ph.maybe(0.3) else ""
        up = _pick(rng, ("", "", "up", "above the head", "over the head"))
        return " ".join(x for x in (ph.verb(_pick(rng, VERBS["raise_arms"])), arms, up, cnt) if x)
    if p.count and p.action in NOUNS and ph.maybe(0.35):
        verb = ph.verb(_pick(rng, (("performs", "performing"), ("does", "doing"))))
        n = ph.say("count", "a" if p.count == 1 else number(p.count, rng))
        return " ".join(x for x in (verb, n, plural(NOUNS[p.action], p.count), extra) if x)
    verb = ph.verb(_pick(rng, VERBS[p.action]))
    if p.action in ("squat", "bow") and ph.maybe(0.4):
        verb += " down"
    cnt = ph.say("count", times(p.count, rng)) if p.count and ph.maybe(0.6) else ""
    if cnt and ph.maybe(0.5):
        return " ".join(x for x in (verb, cnt, extra) if x)
    return " ".join(x for x in (verb, extra, cnt) if x)


def phrase(prim: Primitive, rng: np.random.Generator, ing: bool = False,
           poss: str = "the") -> tuple[str, Primitive]:
    """One verb phrase for ``prim`` and the masked primitive it states."""
    ph = _Phrase(rng, prim, ing, poss)
    a = prim.action
    if a in LOCOMOTION:
        text = _locomotion(ph)
    elif a == "turn":
        text = _turn(ph)
    elif a in ("wave", "punch", "wipe"):
        text = _limb_action(ph, "hand")
    elif a in ("kick", "stomp"):
        text = _limb_action(ph, _pick(rng, ("foot", "leg")) if a == "kick" else "foot")
    else:
        text = _repeat_action(ph)
    return " ".join(text.split()), prim.masked(ph.said)


def sentence(prims: list[Primitive], rng: np.random.Generator) -> tuple[str, list[Primitive]]:
    """One sentence for a sample's primitives (body primitives in order, overlays after
    the body primitive they ride on). Returns the text and the masked primitives it states."""
    subject = _pick(rng, SUBJECTS)
    poss = _pick(rng, POSSESSIVE[subject])
    ing = rng.random() < 0.3
    # group overlays with their body primitive
    groups: list[list[Primitive]] = []
    for p in prims:
        if p.layer == "upper" and groups:
            groups[-1].append(p)
        else:
            groups.append([p])
    clauses, stated = [], []
    for g in groups:
        body_text, body_said = phrase(g[0], rng, ing, poss)
        if len(g) == 1:
            clauses.append(body_text)
            stated.append(body_said)
            continue
        up_said = []
        if rng.random() < 0.5:
            up_text, s = phrase(g[1], rng, True, poss)
            text = f"{body_text} while {up_text}"
        else:
            up_text, s = phrase(g[1], rng, ing, poss)
            body_ing, body_said = phrase(g[0], rng, True, poss)
            text = f"{up_text} while {body_ing}"
        up_said.append(s)
        clauses.append(text)
        stated.extend([body_said] + up_said)
    aux = "is " if ing else ""
    if len(clauses) == 1:
        body = clauses[0]
    else:
        joins = (", then ", " and then ", ", and then ", " and ", ", after that ")
        body = clauses[0]
        for i, c in enumerate(clauses[1:], start=1):
            j = ", " if (i < len(clauses) - 1 and rng.random() < 0.5) else _pick(rng, joins)
            body += j + c
        if rng.random() < 0.15 and not ing:
            body = "first " + body
    text = f"{subject} {aux}{body}"
    text = text[0].upper() + text[1:] if rng.random() < 0.8 else text
    if rng.random() < 0.75:
        text += "."
    return text, stated


def sentences(prims: list[Primitive], rng: np.random.Generator, n: int,
              max_tries: int = 40) -> list[tuple[str, list[Primitive]]]:
    """``n`` distinct sentences (fewer only if the grammar runs out of variants)."""
    out, seen = [], set()
    for _ in range(max_tries):
        text, stated = sentence(prims, rng)
        norm = text.lower().rstrip(".")
        if norm not in seen:
            seen.add(norm)
            out.append((text, stated))
            if len(out) == n:
                break
    return out

"""Findings -> English, in the style of KIT-ML's annotations: "a person walks forward, turns
left, then sits down on the floor".

Every phrase comes from one finding (:func:`phrase`), so that ``describe --explain`` can print
the evidence beside it; a sentence joins at most :data:`MAX_CLAUSES` phrases in time order and
never says the same phrase twice. Words of mood or style are never produced here: the
geometry does not show them.
"""
from __future__ import annotations

from motionlang.analysis.evidence import Finding
from motionlang.analysis.locomotion import JOG_UPTO
from motionlang.analysis.words import ACTION_WORDS

SUBJECT = "a person"
#: what is said when the analysis finds nothing it is sure of
CANNOT_TELL = "a person moves in a way the analysis cannot tell"
MAX_CLAUSES = 3
#: the detail level adds the counts and angles that the terse level leaves out
LEVELS = ("terse", "detailed")


def times(n: int) -> str:
    return "" if n <= 1 else " twice" if n == 2 else f" {n} times"


def _hand(side: str | None, limb: str = "hand") -> str:
    if side == "both":
        return f"both {limb}s" if limb != "foot" else "both feet"
    return f"the {side} {limb}" if side else f"a {limb}"


def phrase(f: Finding, *, level: str = "terse", first: bool = False) -> str:
    """One verb phrase (third person, present) for a finding. ``first``: the finding
    opens the take (a posture held from the start is "sits", entered later "sits
    down")."""
    d = f.detail
    detailed = level == "detailed"
    lab = f.label
    if lab in ("walk", "run"):
        verb = "walks" if lab == "walk" else "jogs" if _froude(f) < JOG_UPTO else "runs"
        if d.get("in_place"):
            return f"{verb} in place" + (f" ({d['steps']} steps)" if detailed else "")
        direction = d.get("direction", "forward")
        path = d.get("path", "straight")
        if direction in ("left", "right"):
            text = f"steps sideways to the {direction}" if lab == "walk" else \
                f"{verb} sideways to the {direction}"
        elif path == "in a circle":
            text = f"{verb} in a circle"
        else:
            text = f"{verb} {direction}"
            if path.startswith("curving"):
                text += f" in a curve to the {path.split()[-1]}"
        speed = d.get("speed")
        if speed and lab == "walk":
            text += f" {speed}"
        if detailed and d.get("steps"):
            text += f" ({d['steps']} steps, {d.get('speed_ms', 0):.1f} m/s)"
        return text
    if lab == "jump":
        direction = d.get("direction", "up")
        text = {"forward": "jumps forward", "up": "jumps up", "down": "jumps down"}[direction]
        return text + times(f.count)
    if lab == "hop":
        return f"hops on the {f.side} leg" + times(f.count)
    if lab == "turn":
        angle = d.get("rounded", 90)
        if angle >= 180 or abs(d.get("angle", 0)) >= 150:
            return "turns around"
        return f"turns {f.side}" + (f" about {angle} degrees" if detailed or angle != 90
                                    else "")
    if lab == "spin":
        return "spins around" + times(f.count)
    if lab == "climb":
        return "climbs down" if d.get("direction") == "down" else "climbs up"
    if lab == "step_up":
        return "steps up" + (" onto something" if f.count == 1 else "")
    if lab == "step_down":
        return "steps down"
    if lab == "hang":
        return "hangs by the hands, moving along" if d.get("travelled") else \
            "hangs by the hands"
    held = first and f.start < 0.5
    if lab == "sit":
        where = " on the floor" if d.get("seat") == "floor" else ""
        return ("sits" if held else "sits down") + where
    if lab == "lie":
        way = "on the back" if d.get("face") == "up" else "face down"
        return ("lies " if held else "lies down ") + way
    if lab == "kneel":
        knee = "on both knees" if f.side == "both" else f"on the {f.side} knee"
        return ("kneels " if held else "kneels down ") + knee
    if lab == "squat":
        return f"squats{times(f.count)}" if f.count > 1 else "squats" if held else \
            "squats down"
    if lab == "crouch":
        return "crouches" if held else "crouches down"
    if lab == "all_fours":
        return "is on hands and knees" if held else "gets down on hands and knees"
    if lab == "crawl":
        return "crawls forward"
    if lab == "one_leg":
        return f"balances on the {f.side} leg"
    if lab == "arms_out":
        return "holds both arms out"
    if lab == "stand":
        return "stands still"
    if lab == "get_up":
        return "gets up"
    if lab == "raise":
        return f"raises {_hand(f.side)}"
    if lab == "wave":
        return f"waves with {_hand(f.side)}"
    if lab == "punch":
        return "punches" + (f" with {_hand(f.side)}" if f.side else "") + times(f.count)
    if lab == "kick":
        return "kicks" + (f" with {_hand(f.side, 'leg')}" if f.side else "") + times(f.count)
    if lab == "reach":
        return f"reaches forward with {_hand(f.side)}"
    if lab == "bend":
        return "bends over"
    if lab == "bow":
        return "bows" + times(f.count)
    if lab == "touch_floor":
        return "touches the floor"
    if lab == "clap":
        return "claps" + times(f.count)
    if lab == "dance":
        moves = [_MOVE_NOUNS[m] for m in d.get("moves", ()) if m in _MOVE_NOUNS]
        return "dances" + (f" ({', '.join(moves)})" if detailed and moves else "")
    raise ValueError(f"no phrase for the label {lab!r}")


#: what a dance's detailed phrase calls the movements it is made of
_MOVE_NOUNS = {"kick": "kicks", "spin": "spins", "one_leg": "balances on one leg",
               "raise": "raised arms", "wave": "waves", "arms_out": "arms held out",
               "clap": "claps", "jump": "leaps", "hop": "hops", "bow": "bows"}


def _froude(f: Finding) -> float:
    return float(f.detail.get("froude", JOG_UPTO))


def join(phrases: list[str], subject: str = SUBJECT) -> str:
    """"a person A", "a person A and then B", "a person A, B, then C"."""
    phrases = list(dict.fromkeys(p for p in phrases if p))
    if not phrases:
        return CANNOT_TELL
    # "kicks twice, spins around twice" says a word twice within four: the second otherwise
    for i in range(1, len(phrases)):
        if phrases[i].endswith(" twice") and phrases[i - 1].endswith(" twice"):
            phrases[i] = phrases[i].removesuffix(" twice") + " two times"
    if len(phrases) == 1:
        body = phrases[0]
    elif len(phrases) == 2:
        body = f"{phrases[0]} and then {phrases[1]}"
    else:
        body = ", ".join(phrases[:-1]) + f", then {phrases[-1]}"
    return tidy(f"{subject} {body}")


def tidy(text: str) -> str:
    """A sentence without a word or a phrase said twice in a row ("punk punk", "6 steps 6
    steps"), spaces normalised."""
    words = text.split()
    changed = True
    while changed:
        changed = False
        for n in range(1, 5):
            for i in range(len(words) - 2 * n + 1):
                if words[i:i + n] == words[i + n:i + 2 * n]:
                    del words[i + n:i + 2 * n]
                    changed = True
                    break
            if changed:
                break
    return " ".join(words)


#: words a sentence may well say twice ("walks forward, then walks back" says "walks" twice
#: far apart, which is English; these may also come close together)
_FREE = frozenset("a an the and then with of to in on at his her their its is are while "
                  "times left right both hand hands leg legs foot feet forward forwards "
                  "backward backwards up down around sideways".split())


def repeats(text: str) -> bool:
    """Whether a sentence says a word or a phrase twice in a row (what :func:`tidy`
    removes), a pair of words twice anywhere, or one content word twice within four words
    ("3 squats 3 times squats")."""
    words = text.lower().replace(",", " ").split()
    if tidy(" ".join(words)) != " ".join(words):
        return True
    pairs = [p for p in zip(words, words[1:]) if not set(p) & _FREE]
    if len(set(pairs)) < len(pairs):
        return True
    return any(w.isalpha() and w not in _FREE and w in words[i + 1:i + 4]
               for i, w in enumerate(words))


#: the forms of the action words a subject can take ("walks", "bows", "squats")
THIRD_PERSON = frozenset(w for ws in ACTION_WORDS.values() for w in ws
                          if w.endswith("s") and not w.endswith("ss"))


#: action verbs that take an object, which may be an action's noun ("throws punches",
#: "turns cartwheels", "lifts boxes")
_TRANSITIVE = frozenset("throws tosses turns lifts raises grabs picks hits strikes touches "
                        "swings kicks punches".split())
#: verbs that never follow an action verb ("a person jumps does some squats")
_AUXILIARY = frozenset("does did is was has makes takes goes gets".split())


def garbled(text: str) -> bool:
    """Whether a sentence is broken English a model stumbled into: no subject before its
    verb ("a walks forward", "an is walking"), two verbs in a row ("a person jumps bows", "jumps squats",
    "jumps does some squats"; a comma between them is a list: "walks, turns around"), or
    an action verb that takes no object followed by "the way" ("a person jumps the way";
    one shows or points the way)."""
    words = text.lower().split()
    if len(words) >= 2 and words[0] in ("a", "an", "the") and (
            words[1] in THIRD_PERSON or words[1] in _AUXILIARY):   # "an is walking"
        return True
    if words[:2] == ["both", "person"]:   # "both person raises both hands"
        return True
    if any(a in THIRD_PERSON and a not in _TRANSITIVE and b == "the" and c in ("way", "way,")
           for a, b, c in zip(words, words[1:], words[2:])):   # "jumps the way" (not "shows")
        return True
    return any(a in THIRD_PERSON and a not in _TRANSITIVE and (
        b in THIRD_PERSON or b in _AUXILIARY) for a, b in zip(words, words[1:]))

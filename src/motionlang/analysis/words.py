"""Which actions a sentence names: the same coarse actions the analysis reports
(``analysis.ACTION``), read from the words of a caption, a query or a generated sentence.

One table of verbs and their forms per action, so that ``describe`` can ask whether a model's
sentence agrees with the body, ``check`` which actions of a sentence a motion shows, and
``generate`` whether a model ever learnt an action it is asked for.
"""
from __future__ import annotations

import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

#: coarse action -> the words that name it (every form a caption uses)
ACTION_WORDS: dict[str, tuple[str, ...]] = {
    "walk": ("walk", "walks", "walking", "walked", "stroll", "strolls", "strolling",
             "march", "marches", "marching", "steps", "step", "stepping", "paces", "pacing",
             "wanders", "wandering", "strides", "striding", "shuffles", "shuffling",
             "wander", "wandered", "strode", "amble", "ambles", "ambling",
             "ambled", "saunter", "saunters", "sauntering", "sauntered", "trudge", "trudges",
             "trudging", "trudged", "plod", "plods", "plodding", "plodded", "meander",
             "meanders", "meandering", "meandered", "promenade", "promenades",
             "promenading", "traipse", "traipses", "traipsing", "mosey", "moseys",
             "moseying", "hiking", "tiptoeing", "sidestep", "sidesteps", "sidestepping",
             "sidestepped"),
    "run": ("run", "runs", "running", "ran", "jog", "jogs", "jogging", "jogged", "sprint",
            "sprints", "sprinting", "dash", "dashes", "dashing", "trot", "trots", "trotting",
            "sprinted", "dashed", "trotted", "races", "racing", "raced", "rushes",
            "rushing", "rushed", "hurries", "hurrying", "hurried", "scurry",
            "scurries", "scurrying", "scurried", "scamper", "scampers", "scampering",
            "gallop", "gallops", "galloping", "lope", "lopes", "loping"),
    "jump": ("jump", "jumps", "jumping", "jumped", "hop", "hops", "hopping", "hopped", "leap",
             "leaps", "leaping", "leapt", "leaped", "vault", "vaults", "vaulting"),
    "climb": ("climb", "climbs", "climbing", "climbed", "hang", "hangs", "hanging", "scale",
              "scales", "scaling", "clambers", "clambering"),
    "punch": ("punch", "punches", "punching", "punched", "box", "boxes", "boxing", "jab",
              "jabs", "jabbing", "strike", "strikes", "striking", "hits", "hitting"),
    "kick": ("kick", "kicks", "kicking", "kicked"),
    "crouch": ("crouch", "crouches", "crouching", "crouched", "squat", "squats", "squatting",
               "squatted", "duck", "ducks", "ducking", "hunker", "hunkers", "hunkering",
               "hunkered"),
    "sit": ("sit", "sits", "sitting", "sat", "seated", "seats"),
    "lie": ("lie", "lies", "lying", "lay", "lays", "laying", "prone", "supine"),
    "kneel": ("kneel", "kneels", "kneeling", "knelt"),
    "crawl": ("crawl", "crawls", "crawling", "crawled"),
    "balance": ("balance", "balances", "balancing", "balanced"),
    "wave": ("wave", "waves", "waving", "waved", "hail", "hails", "hailing", "hailed"),
    "raise": ("raise", "raises", "raising", "raised", "lift", "lifts", "lifting", "lifted",
              "hoist", "hoists", "hoisting", "hoisted"),
    "clap": ("clap", "claps", "clapping", "clapped", "applaud", "applauds", "applauding"),
    "turn": ("turn", "turns", "turning", "turned", "rotate", "rotates", "rotating", "veer",
             "veers", "veering", "veered", "swerve", "swerves", "swerving", "swerved",
             "pivot", "pivots", "pivoting", "pivoted"),
    "spin": ("spin", "spins", "spinning", "spun", "pirouette", "pirouettes", "twirl",
             "twirls", "twirling"),
    "bow": ("bow", "bows", "bowing", "bowed"),
    "bend": ("bend", "bends", "bending", "bent", "stoop", "stoops", "stooping", "pick",
             "picks", "picking", "touches", "touch"),
    "reach": ("reach", "reaches", "reaching", "reached", "grab", "grabs", "grabbing"),
    "stand": ("stand", "stands", "standing", "stood", "still"),
    "dance": ("dance", "dances", "dancing", "danced", "ballet", "ballerina"),
    # named so that a check can say it cannot tell, rather than pass over the word
    "throw": ("throw", "throws", "throwing", "threw", "toss", "tosses", "tossing"),
    "fall": ("fall", "falls", "falling", "fell", "trip", "trips", "stumble", "stumbles"),
    "cartwheel": ("cartwheel", "cartwheels", "somersault", "somersaults", "flip", "flips",
                  "backflip", "backflips"),
}
_POSSESSIVE = r"(?:his|her|their|its|the|a|one|both|\s)*"
#: a hand or arm as a sentence names it, with its side ("the left hand", "both arms")
_LIMB = (r"(?:(?:his|her|their|its|the|a|one|both|left|right|just|only)\s+)*"
         r"(?:hands?|arms?|palms?|fists?)")
#: the same of hands alone: arms swung back and forth are a walk's, hands so are a wave
_HAND = (r"(?:(?:his|her|their|its|the|a|one|both|left|right|just|only)\s+)*"
         r"(?:hands?|palms?)")
#: upward, as a sentence says it of a hand
_HIGH = (r"(?:overhead|high|skywards?|in(?:to)?\s+the\s+air|(?:above|over)\s+(?:his|her|their|"
         r"the)\s+head|to(?:wards?)?\s+the\s+(?:sky|ceiling))")
#: ... where a bare "up" is no raise when a place follows ("up to his mouth", "up in front
#: of the face": a guard) or it goes down again ("up and down")
_UP = (rf"(?:straight\s+)?(?:up(?:wards?)?(?:\s+{_HIGH}|(?!\s+(?:to|towards?|in\s+front|in\s+a|"
       rf"into|at|by|near|against|before|and\s+down|or\s+down)\b))|{_HIGH})")
#: a side a path bends to ("to the left", "toward her right", "off to the right"), not a
#: limb's ("curves his left arm")
_BEND = (r"(?:\s+(?:off|round|around|away))?\s+(?:(?:to|towards?)\s+(?:the\s+|his\s+|her\s+|"
         r"their\s+)?|the\s+)?(?:left|right)(?!\s+(?:arms?|hands?|legs?|feet|foot|knees?|"
         r"elbows?|shoulders?|hips?)\b)")
#: what can follow "takes a left": the end of a clause, a joint or a place, not a noun
_CLAUSE_GOES_ON = (r"(?=\s*(?:$|[,;.]|(?:and|then|at|into|onto|to|towards?|after|before|while|"
                   r"here|there|again)\b))")
#: phrases that name an action their words alone do not (or name another: "standing on one
#: leg" is balancing, not standing); read before the single words, whose words they take
PHRASES: tuple[tuple[re.Pattern[str], str], ...] = tuple(
    (re.compile(p), a) for p, a in (
        (r"\b(?:(?:stands?|standing|stood|balances?|balancing|poses?|posing|remains?|"
         r"stays?)\s+(?:still\s+)?)?on\s+(?:one|a single|(?:his|her|their|the)\s+"
         r"(?:left|right))\s+(?:leg|foot)\b", "balance"),
        (rf"\bon\s+(?:all fours|{_POSSESSIVE}hands and knees)\b", "crawl"),
        (rf"\b(?:gets?|getting|goes|going|went|drops?|dropping)\s+down\s+on\s+"
         rf"{_POSSESSIVE}knees?\b", "kneel"),
        (rf"\bon\s+{_POSSESSIVE}knees?\b", "kneel"),
        (r"\b(?:takes?|taking|took|has|have)\s+a\s+seat\b", "sit"),
        (r"\b(?:gets?|getting|got)\s+up\b|\b(?:rises?|rising|rose)\s+to\s+(?:his|her|their|"
         r"the)\s+feet\b", "stand"),
        (rf"\bon\s+{_POSSESSIVE}(?:back|belly|stomach|side)\b", "lie"),
        (r"\b(?:goes|going|went|walks?|walking)\s+up\s+(?:the\s+)?(?:stairs|steps|ladder)\b",
         "climb"),
    ))
#: phrases in other words for an action its own verb names: read as :data:`PHRASES` are,
#: and said with the action's verb in a canonical caption (``datasets.canonical``); a
#: group ``keep`` holds the words that stay (the hand and its side)
PARAPHRASES: tuple[tuple[re.Pattern[str], str], ...] = tuple(
    (re.compile(p), a) for p, a in (
        (rf"\b(?:puts?|putting|sticks?|sticking|stuck|shoots?|shooting|shot|throws?|throwing|"
         rf"threw|holds?|holding|held|thrusts?|thrusting|gets?|getting|got|brings?|bringing|"
         rf"brought|stretch(?:es)?|stretching|stretched|extends?|extending|extended|pokes?|"
         rf"poking)\s+(?P<keep>{_LIMB})\s+{_UP}", "raise"),
        (rf"\breach(?:es|ing|ed)?\s+(?:{_UP}|for\s+the\s+(?:sky|ceiling))", "raise"),
        (r"\b(?:says?|saying|said|signals?|signall?ing|signall?ed|waves?|waving|waved)\s+"
         r"(?:hello|hi|goodbye|good-bye|bye|farewell)\b", "wave"),
        (r"\bbids?\s+(?:\w+\s+)?(?:farewell|goodbye|good-bye)\b", "wave"),
        # a greeting is a wave unless the sentence says how it is made ("with a bow")
        (r"(?<!\bin )(?<!\ba )\bgreet(?:s|ing|ed)?\b(?![^,;.]*\b(?:bows?|bowing|nods?|nodding|"
         r"handshakes?|shak\w*\s+hands?|hugs?|hugging|kiss\w*)\b)", "wave"),
        (r"(?<!\bthe )(?<!\ba )\bflag(?:s|ging|ged)?\s+(?:\w+\s+)?down\b", "wave"),
        (rf"\b(?:swings?|swinging|swung|shakes?|shaking|shook|sways?|swaying|swayed|wags?|"
         rf"wagging|wagged|moves?|moving|moved)\s+(?P<keep>{_HAND})\s+(?:from\s+)?"
         rf"(?:side\s+to\s+side|back\s+and\s+forth|to\s+and\s+fro)", "wave"),
        (rf"\b(?:takes?|taking|took|makes?|making|made|hangs?|hanging|hung)\s+a\s+"
         rf"(?P<keep>left|right)(?:\s+turn)?{_CLAUSE_GOES_ON}", "turn"),
        (r"\bchang(?:es|ing|ed|e)\s+(?:of\s+)?directions?\b", "turn"),
        (r"\b(?:goes|going|went|heads?|heading|headed|comes?|coming|came)\s+(?:round|around)\s+"
         r"(?:a|the)\s+(?:corner|bend)\b", "turn"),
        (rf"(?<!\ba )(?<!\bthe )(?<!degree )\b(?:bears|bearing|bore|curves|curving|curved|wheels|"
         rf"wheeling|wheeled)(?={_BEND})", "turn"),
        (r"\b(?:(?:puts?|putting|places?|placing|sets?|setting)\s+)?one\s+foot\s+(?:after|"
         r"in\s+front\s+of)\s+the\s+other\b", "walk"),
        (r"\b(?:heads?|heading|headed|goes|going|went|moves?|moving|moved|travels?|"
         r"travell?ing|travell?ed|crosses|crossing|crossed|proceeds?|proceeding|proceeded|"
         r"makes?\s+(?:his|her|their|its)\s+way|making\s+(?:his|her|their|its)\s+way)"
         r"(?=(?:\s+\w+){0,4}?\s+on\s+foot\b)", "walk"),
        (r"\bthrows?\s+(?:(?:a|an|the|his|her|some|few|two|three|quick|fast|hard|straight)\s+)"
         r"{0,3}(?:(?P<keep>left|right)\s+)?(?:(?:quick|fast|hard|straight)\s+)?(?:punch|"
         r"punches|jabs?|hooks?|uppercuts?|crosses)\b", "punch"),
        (r"\b(?:makes?|making|made|does|doing|did|takes?|taking|took|pulls?|pulling|pulled)\s+"
         r"an?\s+u[\s-]?turns?\b", "turn"),
    ))
_INDEX = {w: a for a, ws in ACTION_WORDS.items() for w in ws}
_TOKEN = re.compile(r"[a-z]+")
#: actions that answer for one another when two readers compare (a hop is a jump, a squat is
#: a crouch, a pick-up bends over)
COMPATIBLE = {"spin": {"turn"}, "turn": {"spin"}, "raise": {"wave", "reach"},
              "wave": {"raise"}, "bow": {"bend"}, "bend": {"bow", "crouch"},
              "crouch": {"bend", "kneel"}, "kneel": {"crouch"}, "climb": {"jump"},
              "crawl": {"kneel"}}


def _found(text: str) -> list[tuple[int, int, str]]:
    """``(start, end, action)`` of every phrase and word of ``text`` (lower case) that names
    an action, in order: its :data:`PHRASES` first, then the words outside them."""
    found: list[tuple[int, int, str]] = []
    taken = [False] * len(text)
    for pattern, action in (*PHRASES, *PARAPHRASES):
        for m in pattern.finditer(text):
            if not any(taken[m.start():m.end()]):
                found.append((m.start(), m.end(), action))
                taken[m.start():m.end()] = [True] * (m.end() - m.start())
    for m in _TOKEN.finditer(text):
        a = _INDEX.get(m.group())
        if a is not None and not taken[m.start()]:
            found.append((m.start(), m.end(), a))
    return sorted(found)


def actions_named(text: str) -> list[str]:
    """The coarse actions a sentence names, in the order it names them, each once: its
    :data:`PHRASES` first, then the words of :data:`ACTION_WORDS` outside them."""
    out: list[str] = []
    for _, _, a in _found(text.lower()):
        if a not in out:
            out.append(a)
    return out


@dataclass(frozen=True)
class Mention:
    """How a sentence names one action: ``side`` ("left", "right", "both" or None) and
    ``direction`` ("forward", "backwards", "sideways", "in place" or None) from the words after it up
    to the next action or clause; ``negated``: "not", "never", "without" just before it;
    ``after_previous``: "then", "after that", "followed by", "before" between it and the
    action named before it ("walks before jumping": the jump comes after the walk; "before
    that" looks back, and is no order); ``path``: "in a circle" where the sentence says
    so; ``pace``: "slow" or "fast" from its words of speed ("slowly walks", "runs fast")."""

    action: str
    side: str | None = None
    direction: str | None = None
    negated: bool = False
    after_previous: bool = False
    path: str | None = None
    pace: str | None = None


_CLAUSE_END = re.compile(r"[,;.]|\band\b|\bthen\b|\bwhile\b")
_SIDE = re.compile(r"\b(left|right|both)\b")
_DIRECTION = {"forward": "forward", "forwards": "forward", "ahead": "forward",
              "backward": "backwards", "backwards": "backwards",
              "sideways": "sideways", "sidewards": "sideways"}
_IN_PLACE = re.compile(r"\b(?:in place|on the spot|on the treadmill|on a treadmill)\b")
_CIRCLE = re.compile(r"\bin (?:a |one )?(?:full |big |small |wide )?circles?\b")
_PACE = {"slowly": "slow", "slow": "slow", "leisurely": "slow", "unhurriedly": "slow",
         "sluggishly": "slow", "quickly": "fast", "quick": "fast", "fast": "fast",
         "briskly": "fast", "rapidly": "fast", "hurriedly": "fast", "swiftly": "fast"}
_NEGATION = re.compile(r"(?:\b(?:not|never|without|no longer|no one|no-one|nobody|noone)|"
                       r"n't)\s+$")
_SEQUENCE = re.compile(r"\bthen\b|\bafter(?:wards| that)\b|\bfollowed by\b|"
                       r"\bbefore\b(?!\s+(?:that|this|it|then|so)\b)")


def mentions(text: str) -> list[Mention]:
    """Each action ``text`` names, once (its first naming), with the side, direction,
    negation and order the sentence gives it (:class:`Mention`)."""
    low = text.lower()
    found = _found(low)
    out: list[Mention] = []
    seen: set[str] = set()
    for i, (start, end, action) in enumerate(found):
        if action in seen:
            continue
        seen.add(action)
        nxt = found[i + 1][0] if i + 1 < len(found) else len(low)
        after = low[end:nxt]
        cut = _CLAUSE_END.search(after)
        clause = after[:cut.start()] if cut else after
        sides = _SIDE.findall(low[start:end] + clause)   # "balances on the left leg"
        words = _TOKEN.findall(clause)
        direction = "in place" if _IN_PLACE.search(clause) else next(
            (_DIRECTION[w] for w in words if w in _DIRECTION), None)
        before = low[found[i - 1][1] if i else 0:start]
        # "slowly walks" and "walks slowly": the words just before it in its clause too
        lead = _CLAUSE_END.split(before)[-1]
        pace = next((_PACE[w] for w in _TOKEN.findall(lead) + words if w in _PACE), None)
        out.append(Mention(action, sides[0] if sides else None, direction,
                           bool(_NEGATION.search(before)),
                           bool(i and _SEQUENCE.search(before)),
                           "in a circle" if _CIRCLE.search(clause) else None, pace))
    return out


def agrees(named: list[str] | set[str], action: str) -> bool:
    """Whether a sentence that names ``named`` names ``action`` or one answering for it."""
    return any(a == action or action in COMPATIBLE.get(a, ()) for a in named)


def never_learnt(text: str, caption_words) -> tuple[list[str], set[str]]:
    """``(actions text names that no caption word names, actions the captions name)``:
    what a model whose training captions used ``caption_words`` was never shown."""
    learnt = set(actions_named(" ".join(caption_words)))
    return [a for a in actions_named(text) if a not in learnt], learnt


def caption_words(model) -> Sequence[str]:
    """The words of a model's training captions: its ``caption_words`` (a family that
    keeps them: the two-stream and masked models), else its vocabulary's (an L2M's);
    empty where it keeps neither (a file from before)."""
    words = getattr(model, "caption_words", None)
    if words is None:
        words = getattr(getattr(model, "vocab", None), "itos", None)
    return tuple(words or ())


def warn_never_learnt(text: str, model) -> None:
    """One warning when ``text`` asks a model that keeps the words of its training captions
    (:func:`caption_words`) for an action none of those words names, naming the actions it
    can make."""
    never, learnt = never_learnt(text, caption_words(model))
    if never and learnt:
        low = text.lower()   # the sentence's own words for them ("backflip", not cartwheel)
        said = [next(low[a:b] for a, b, act in _found(low) if act == n) for n in never]
        warnings.warn(f"this {getattr(model, 'kind', 'model')} model never learnt to "
                      f"{' or '.join(repr(w) for w in said)} (the actions it can make: "
                      f"{', '.join(sorted(learnt - {'stand'}))})", UserWarning, stacklevel=3)

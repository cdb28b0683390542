"""English for the Bandai Namco labels: a small grammar turning (content, style) into
sentences, and a synonym table for judging whether a description names the style.

The datasets label each take with one action ("content") and one way of doing it
("style"); they have no sentences. :func:`describe` writes several for a label pair,
deterministic given a seed, each :class:`Sentence` keeping its labels. A style is stated
three ways, as annotators of KIT-ML do for manner: in the subject ("an old man walks
forward"), as an adverb before the verb ("someone cheerfully waves their left hand") or
as a phrase after it ("a person raises both arms like a giant"). "normal" is often left
unsaid: :func:`names_style` counts a sentence naming no style as naming "normal".

What the contents are was checked on the takes themselves (21-joint positions, normal
style), where the label alone is unclear: ``walk-left``/``walk-right`` walk diagonally
forward (about 20-30 degrees) facing ahead, ``walk-turn-*`` walk and turn about 90
degrees, ``bye`` waves goodbye with one hand at shoulder height, ``byebye`` with both,
``guide`` sweeps one arm out to show the way, ``respond`` raises one hand above the head,
``call`` holds both hands by the mouth to call out.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from motionlang.datasets.synth.augment import mirror_text  # same layer

#: content label -> verb phrases (third person); ``{p}`` is the subject's possessive
CONTENTS: dict[str, tuple[str, ...]] = {
    "walk": ("walks forward", "walks", "walks straight ahead", "walks forwards"),
    "run": ("runs forward", "runs", "jogs forward", "runs straight ahead"),
    "dash": ("dashes forward", "sprints forward", "runs forward very fast", "sprints"),
    "walk-back": ("walks backward", "walks backwards", "steps backwards"),
    "walk-left": ("walks diagonally to the left", "walks forward and to the left",
                  "walks ahead bearing to the left"),
    "walk-right": ("walks diagonally to the right", "walks forward and to the right",
                   "walks ahead bearing to the right"),
    "walk-turn-left": ("walks and turns to the left", "walks forward and turns left",
                       "walks and makes a left turn"),
    "walk-turn-right": ("walks and turns to the right", "walks forward and turns right",
                        "walks and makes a right turn"),
    "bow": ("bows", "bows down", "takes a bow", "bows from the waist"),
    "bye": ("waves goodbye", "waves goodbye with one hand", "waves a hand to say goodbye"),
    "byebye": ("waves goodbye with both hands", "waves both hands to say goodbye",
               "waves bye bye with both hands"),
    "guide": ("shows the way with {p} arm", "gestures the way with an open hand",
              "points the way with a sweep of the arm"),
    "respond": ("raises a hand to answer", "answers by raising a hand",
                "puts a hand up to respond"),
    "call": ("calls out to someone", "calls out with {p} hands around the mouth",
             "shouts to someone far away"),
    "punch": ("punches", "throws punches", "punches forward"),
    "kick": ("kicks", "kicks forward", "does some kicks"),
    "slash": ("slashes with a sword", "swings a sword", "makes slashing moves"),
    "dance-short": ("dances", "does a short dance", "dances briefly"),
    "dance-long": ("dances", "does a long dance", "dances for a while"),
    "wave-both-hands": ("waves both hands", "waves with both hands", "waves both arms"),
    "wave-left-hand": ("waves with the left hand", "waves {p} left hand",
                       "waves the left hand"),
    "wave-right-hand": ("waves with the right hand", "waves {p} right hand",
                        "waves the right hand"),
    "raise-up-both-hands": ("raises both arms", "raises both hands", "lifts both arms up"),
    "raise-up-left-hand": ("raises the left hand", "raises {p} left arm",
                           "lifts {p} left hand up"),
    "raise-up-right-hand": ("raises the right hand", "raises {p} right arm",
                            "lifts {p} right hand up"),
}
#: a content and its mirror image (left/right swapped); contents not here mirror to themselves
MIRROR_CONTENT = {f"{a}-left{b}": f"{a}-right{b}" for a, b in (
    ("walk", ""), ("walk-turn", ""), ("wave", "-hand"), ("raise-up", "-hand"))}
MIRROR_CONTENT.update({v: k for k, v in MIRROR_CONTENT.items()})

NEUTRAL = (("a person", "their"), ("someone", "their"), ("a man", "his"),
           ("a woman", "her"), ("the person", "their"), ("a human", "their"))


@dataclass(frozen=True)
class Style:
    """How a style is said. adverbs: single words placed before the verb; phrases: after
    the verb phrase; subjects: (subject, possessive); synonyms: words and phrases that name
    the style (for judging descriptions), the above's style words among them."""

    adverbs: tuple[str, ...]
    phrases: tuple[str, ...]
    subjects: tuple[tuple[str, str], ...]
    synonyms: tuple[str, ...]


def _style(adverbs: str, phrases: str, subjects: str, synonyms: str) -> Style:
    """Tables below as '|'-separated strings; a subject ends in its possessive after ':'."""
    split = (lambda s: tuple(x.strip() for x in s.split("|") if x.strip()))
    return Style(split(adverbs), split(phrases),
                 tuple(tuple(s.split(":")) for s in split(subjects)), split(synonyms))


_OLD = "old|elderly|aged|senior|old man|old woman|old person"
_TIRED = "tired|tiredly|weary|wearily|exhausted|exhaustion|worn out|fatigued|sluggishly"
_YOUNG = "young|youthful|youthfully|youngster|teenager|child|childish|childishly|kid"
STYLES: dict[str, Style] = {
    "normal": _style("normally|casually", "in a normal way|in an ordinary way", "",
                     "normal|normally|casual|casually|ordinary|regular"),
    "happy": _style("happily|cheerfully|joyfully", "in a happy way|with joy",
                    "a happy person:their|a cheerful man:his|a joyful woman:her",
                    "happy|happily|cheerful|cheerfully|joyful|joyfully|joy|glad|gladly"),
    "sad": _style("sadly|gloomily|sorrowfully", "in a sad way|with a heavy heart",
                  "a sad person:their|an unhappy man:his|a sad woman:her",
                  "sad|sadly|gloomy|gloomily|sorrowful|sorrowfully|unhappy|heavy heart"),
    "angry": _style("angrily|furiously", "in an angry way|in a rage",
                    "an angry person:their|an angry man:his|a furious woman:her",
                    "angry|angrily|furious|furiously|rage|annoyed|mad"),
    "proud": _style("proudly|haughtily", "with pride|in a proud way",
                    "a proud person:their|a proud man:his|a haughty woman:her",
                    "proud|proudly|pride|haughty|haughtily|arrogant|arrogantly"),
    "not-confident": _style("timidly|shyly|hesitantly", "without confidence|in a timid way",
                            "a timid person:their|a shy man:his|an insecure woman:her",
                            "timid|timidly|shy|shyly|hesitant|hesitantly|insecure|"
                            "without confidence|not confident|unconfident|unconfidently"),
    "masculinity": _style("manfully", "in a manly way|in a masculine way",
                          "a manly man:his|a macho man:his|a masculine person:their",
                          "manly|manfully|masculine|macho|masculinity"),
    "masculine": _style("manfully", "in a masculine way|in a manly way",
                        "a masculine man:his|a macho man:his|a masculine person:their",
                        "masculine|manly|manfully|macho|masculinity"),
    "feminine": _style("daintily", "in a feminine way|in a ladylike way",
                       "a feminine woman:her|a ladylike woman:her|a feminine person:their",
                       "feminine|femininely|ladylike|dainty|daintily"),
    "childish": _style("childishly|playfully", "like a child|in a childish way",
                       "a child:their|a little kid:their|a childish person:their",
                       "childish|childishly|child|kid|childlike|playful|playfully"),
    "youthful": _style("youthfully", "like a young person|in a youthful way",
                       "a young person:their|a young man:his|a youthful woman:her",
                       _YOUNG),
    "old": _style("", "like an old man|like an old person|in an old man's way",
                  "an old man:his|an old woman:her|an old person:their", _OLD),
    "elderly": _style("", "like an elderly person|like an old woman",
                      "an elderly person:their|an elderly man:his|an old woman:her", _OLD),
    "tired": _style("tiredly|wearily|sluggishly", "in a tired way",
                    "a tired person:their|a tired man:his|a weary woman:her", _TIRED),
    "exhausted": _style("wearily", "in an exhausted way|with exhaustion",
                        "an exhausted person:their|an exhausted man:his|"
                        "a worn out woman:her", _TIRED),
    "active": _style("energetically|actively|vigorously", "with a lot of energy",
                     "an energetic person:their|an active man:his|a lively woman:her",
                     "active|actively|energetic|energetically|energy|vigorous|"
                     "vigorously|lively"),
    "musical": _style("theatrically|rhythmically", "like in a musical|with theatrical flair",
                      "a musical performer:their|a stage actor:his|a theatrical woman:her",
                      "musical|theatrical|theatrically|rhythmic|rhythmically|stage actor|"
                      "performer"),
    "giant": _style("heavily|ponderously", "like a giant|with lumbering movements",
                    "a giant:his|a huge man:his|a giant person:their",
                    "giant|huge|heavily|ponderous|ponderously|lumbering|hulking|enormous"),
    "chimpira": _style("menacingly|swaggeringly", "like a thug|like a street punk",
                       "a thug:his|a street punk:his|a delinquent:their",
                       "thug|thuggish|punk|hoodlum|delinquent|menacing|menacingly|"
                       "swagger|swaggering|swaggeringly|chimpira"),
}


@dataclass(frozen=True)
class Sentence:
    """One description and the labels it describes. states_style: the style is in the
    words (always, except some "normal" sentences)."""

    text: str
    content: str
    style: str
    states_style: bool = True


def _pick(rng: np.random.Generator, seq):
    return seq[int(rng.integers(len(seq)))]


def sentence(content: str, style: str, rng: np.random.Generator) -> Sentence:
    """One sentence for a (content, style) pair, drawn with ``rng``.

    Raises:
        KeyError: an unknown content or style label.
    """
    verbs, st = CONTENTS[content], STYLES[style]
    forms = [f for f, ok in (("subject", st.subjects), ("adverb", st.adverbs),
                             ("phrase", st.phrases)) if ok]
    if style == "normal":
        forms += ["plain", "plain"]
    form = _pick(rng, forms)
    subject, poss = _pick(rng, st.subjects if form == "subject" else NEUTRAL)
    vp = _pick(rng, verbs).format(p=poss)
    if form == "adverb":
        text = f"{subject} {_pick(rng, st.adverbs)} {vp}"
    elif form == "phrase":
        text = f"{subject} {vp} {_pick(rng, st.phrases)}"
    else:
        text = f"{subject} {vp}"
    return Sentence(text, content, style, form != "plain")


def describe(content: str, style: str, n: int = 3, seed: int = 0) -> list[Sentence]:
    """``n`` different sentences for a label pair (fewer if the grammar has fewer), the
    same for the same arguments."""
    rng = np.random.default_rng([seed, *map(ord, f"{content}/{style}")])
    out: dict[str, Sentence] = {}
    for _ in range(20 * n):
        s = sentence(content, style, rng)
        out.setdefault(s.text, s)
        if len(out) == n:
            break
    return list(out.values())


def mirror_sentence(s: Sentence) -> Sentence:
    """Left and right swapped in the words and in the content label."""
    return Sentence(mirror_text(s.text), MIRROR_CONTENT.get(s.content, s.content), s.style,
                    s.states_style)


def _has(text: str, phrase: str) -> bool:
    return re.search(rf"(?<![\w-]){re.escape(phrase)}(?![\w-])", text) is not None


def styles_named(text: str) -> set[str]:
    """The style labels whose synonyms occur in ``text`` (whole words, any case)."""
    low = " ".join(text.lower().split())
    return {name for name, st in STYLES.items() if any(_has(low, w) for w in st.synonyms)}


def names_style(text: str, style: str) -> bool:
    """Whether ``text`` names ``style`` (a synonym from :data:`STYLES`); for "normal", also
    when it names no style at all."""
    found = styles_named(text)
    return style in found or (style == "normal" and not found)


_WALK = "walk|walks|walking|steps|step|stepping"
_RUN = "run|runs|running|jog|jogs|jogging"
_SPRINT = "sprint|sprints|sprinting|dash|dashes|dashing|very fast"
_WAVE = "wave|waves|waving"
_BYE = "goodbye|bye|good bye"
_RAISE = "raise|raises|raising|lift|lifts|lifting|lifted|raised"
_ANSWER = "answer|answers|answering|respond|responds|responding"
_BOTH = "both|two"


def _any(low: str, words: str) -> bool:
    return any(_has(low, w) for w in words.split("|"))


def contents_named(text: str) -> set[str]:
    """The content labels that ``text`` names, by the grammar's words and their synonyms
    ("walks", "runs"/"jogs", "sprints", "waves goodbye", "bows", ...; whole words, any case).

    Contents with a side ("wave-left-hand", "walk-turn-right", ...) need that side's word
    and not the other's; "both" for the two-handed ones. Walks: "backward(s)" makes
    walk-back, "turn(s)" walk-turn-*, a side word alone walk-left/-right (diagonal), none of
    these walk. "dances" names both dance contents unless "short"/"briefly" or "long"/"for a
    while" says which.
    """
    low = " ".join(text.lower().split())
    left, right = _has(low, "left"), _has(low, "right")
    side = "left" if left and not right else "right" if right and not left else ""
    both = _any(low, _BOTH)
    found: set[str] = set()
    if _any(low, _WALK):
        if _any(low, "back|backward|backwards"):
            found.add("walk-back")
        elif _any(low, "turn|turns|turning") and side:
            found.add(f"walk-turn-{side}")
        elif side:
            found.add(f"walk-{side}")
        elif not (left or right):
            found.add("walk")
    running = _any(low, _RUN)
    if _any(low, _SPRINT):
        found.add("dash")
    elif running:
        found.add("run")
    if _any(low, "bow|bows|bowing|bowed"):
        found.add("bow")
    bye = _any(low, _BYE)
    if bye:
        found.add("byebye" if both else "bye")
    elif _any(low, _WAVE):
        if both:
            found.add("wave-both-hands")
        elif side:
            found.add(f"wave-{side}-hand")
    if _has(low, "the way"):
        found.add("guide")
    if _any(low, _ANSWER):
        found.add("respond")
    elif _any(low, _RAISE):
        if both:
            found.add("raise-up-both-hands")
        elif side:
            found.add(f"raise-up-{side}-hand")
    if _any(low, "call|calls|calling|shout|shouts|shouting"):
        found.add("call")
    for verb in ("punch", "kick", "slash"):
        if _any(low, f"{verb}|{verb}s|{verb}es|{verb}ing"):
            found.add(verb)
    if _any(low, "sword"):
        found.add("slash")
    if _any(low, "dance|dances|dancing"):
        short, long_ = _any(low, "short|briefly"), _any(low, "long|for a while")
        found |= ({"dance-short"} if short and not long_ else {"dance-long"} if long_
                  and not short else {"dance-short", "dance-long"})
    return found


def names_content(text: str, content: str) -> bool:
    """Whether ``text`` names the action ``content`` (:func:`contents_named`)."""
    return content in contents_named(text)

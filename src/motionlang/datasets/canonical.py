"""Canonical captions: one rule-based normal form for a sentence about motion, applied to
training captions and to queries alike, so that the many ways people say the same thing
meet before any encoder reads them (MoCHA, 2026, canonicalises captions and queries; its
rule-based variant needs no model at all).

:func:`canonical` keeps what the body does and says it one way: the subject is "a person",
each action verb is its action's own word in the third person ("strolls", "is jogging" ->
"walks", "runs"; ``analysis.words``), number words are digits ("twice" -> "2 times"),
left/right, directions and counts stay, fillers go ("is", "the", "his"), and the words of
style and mood are set apart (returned beside the text, not in it): a style is not an
action, and the takes it was learnt from always carry one. :func:`without_style` is the
style part alone, as ``describe`` uses it.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from motionlang.analysis.sentences import THIRD_PERSON
from motionlang.analysis.words import ACTION_WORDS, PARAPHRASES
from motionlang.datasets.bandai_text import STYLES, styles_named
from motionlang.errors import MotionlangError

_ARTICLE = re.compile(r"\ban (?=[^aeiou\s])")
_MANNER = re.compile(r" (?:in|with) (?:a|an|the)(?: \w+){0,3} (?:way|manner) | at speed ")
_DANGLING = re.compile(r"(?: (?:in|like|with|at|a|an|the|is|of))+$")
#: the article that opens a sentence and the word after it
_BARE_ARTICLE = re.compile(r"^(a|an|the)\s+([a-z]+)\b")


#: other verbs a caption's subject takes ("an old man takes a bow")
_OTHER_VERBS = frozenset("takes does makes goes gets moves performs holds keeps shows "
                         "stands".split())


def _verb_like(word: str) -> bool:
    """Whether a word after a sentence's article is a verb in the third person ("runs",
    "takes"), not a plural subject ("the arms swing")."""
    return word in THIRD_PERSON or word in _OTHER_VERBS
_STYLE_SUBJECTS = sorted({s for st in STYLES.values() for s, _ in st.subjects}, key=len,
                         reverse=True)
_STYLE_PHRASES = sorted({p for st in STYLES.values() for p in (*st.phrases, *st.synonyms)
                         if " " in p}, key=len, reverse=True)
_STYLE_WORDS = {w for st in STYLES.values() for w in (*st.adverbs, *st.synonyms)
                if " " not in w}


def without_style(text: str) -> str:
    """A sentence with its style and mood words taken out ("an insecure woman jumps ahead"
    -> "a woman jumps ahead", "walks forward in a rage" -> "walks forward")."""
    low = f" {' '.join(text.lower().split())} "
    for phrase in _STYLE_PHRASES:
        if phrase not in _STYLE_SUBJECTS:
            low = low.replace(f" {phrase} ", " ")
    for subject in _STYLE_SUBJECTS:
        low = low.replace(f" {subject} ", " a person ")
    words = [w for w in low.split() if w not in _STYLE_WORDS]
    out = " ".join(words)
    # the frame of a style phrase whose words are gone ("in an ... way", "like a"), and a
    # sentence left ending on an article or a preposition
    out = _MANNER.sub(" ", f" {out} ")
    out = _DANGLING.sub("", out.strip())
    # a subject that was all style ("an old woman runs" -> "an runs"): a person is left
    if out.split() != text.lower().split():
        out = _BARE_ARTICLE.sub(lambda m: f"{m.group(1)} person {m.group(2)}" if
                                _verb_like(m.group(2)) else m.group(0), out, count=1)
    return _ARTICLE.sub("a ", out).strip()


#: words of several actions, or of none in most captions: left as they are
_AMBIGUOUS = frozenset({"touch", "touches", "pick", "picks", "picking", "still", "step",
                        "steps", "stepping", "hits", "hitting", "strike", "strikes", "striking",
                        "box", "boxes", "duck", "ducks", "ducking", "scale", "scales",
                        "scaling", "lay", "lays", "laying", "trip", "trips", "bent", "lift",
                        "lifts", "lifting", "lifted"})
#: action -> its own word in the third person
_VERB = {"walk": "walks", "run": "runs", "jump": "jumps", "climb": "climbs",
         "punch": "punches", "kick": "kicks", "crouch": "crouches", "sit": "sits",
         "lie": "lies", "kneel": "kneels", "crawl": "crawls", "balance": "balances",
         "wave": "waves", "raise": "raises", "clap": "claps", "turn": "turns",
         "spin": "spins", "bow": "bows", "bend": "bends", "reach": "reaches",
         "stand": "stands", "dance": "dances", "throw": "throws", "fall": "falls",
         "cartwheel": "cartwheels"}
_CANON = {w: _VERB[a] for a, ws in ACTION_WORDS.items() for w in ws if w not in _AMBIGUOUS}
#: an action word after an article is a noun ("at a trot", "does a jump"): its action's
#: own noun
_NOUN = {w: a for a, ws in ACTION_WORDS.items() for w in ws if w not in _AMBIGUOUS}
_ARTICLES = frozenset({"a", "an", "the"})
_SUBJECT = re.compile(r"^(?:(?:a|an|the|this|that)\s+)?(?:person|man|woman|human|figure|guy|"
                      r"lady|boy|girl|someone|somebody|individual|character|subject|he|she|"
                      r"they|people|actor)\b\s*")
_FILLERS = frozenset({"a", "an", "the", "is", "are", "was", "were", "be", "being", "been",
                      "his", "her", "their", "its", "just", "very", "really", "also"})
_NUMBERS = {"one": "1", "two": "2", "three": "3", "four": "4", "five": "5", "six": "6",
            "seven": "7", "eight": "8", "nine": "9", "ten": "10", "twice": "2 times",
            "thrice": "3 times", "once": "1 time"}
_TOKEN = re.compile(r"[a-z0-9]+(?:'[a-z]+)?|,")
_ARTICLE_WORD = re.compile(r"\b((?:a|an|the)\s+)?([a-z]+)\b")


@dataclass(frozen=True)
class Canonical:
    """A caption's canonical text and the style and mood words set apart from it."""

    text: str
    style: tuple[str, ...] = ()


def styles_in(text: str) -> tuple[str, ...]:
    """The style and mood words and phrases of ``text`` (those :func:`without_style`
    takes out), in its order."""
    low = f" {' '.join(text.lower().split())} "
    found = [(low.find(f" {p} "), p) for p in (*_STYLE_PHRASES, *_STYLE_SUBJECTS)
             if f" {p} " in low]
    words = low.split()
    found += [(low.find(f" {w} "), w) for w in dict.fromkeys(words) if w in _STYLE_WORDS]
    kept: list[str] = []
    for _, p in sorted(found, key=lambda x: (x[0], -len(x[1]))):
        if not any(f" {p} " in f" {k} " for k in kept):   # a word of a phrase already kept
            kept.append(p)
    return tuple(kept)


def canonical(text: str) -> Canonical:
    """The canonical form of a caption or a query (module docstring)::

        >>> canonical("A man is slowly strolling forward, then waves his left hand twice")
        Canonical(text='a person walks forward slowly, then waves left hand 2 times')
    """
    style = styles_in(text)
    plain = without_style(text).lower()
    plain = _SUBJECT.sub("", plain.strip())
    plain = _paraphrased(plain)   # "puts the left hand up" -> "raises the left hand"
    out: list[str] = []
    before = ""
    for raw in _TOKEN.findall(plain):
        after_article, before = before in _ARTICLES, raw
        if raw in _FILLERS:
            continue
        if after_article and raw in _NOUN:
            out += ["a", _NOUN[raw]]
            continue
        tok = _CANON.get(raw, _NUMBERS.get(raw, raw))
        if out and tok == out[-1]:   # "is walking walks" after the fillers go
            continue
        if tok in ("and", "then") and (not out or out[-1] == "and"):
            continue   # the joint of words that went ("proudly and happily walks")
        out.append(tok)
    body = " ".join(out).replace(" ,", ",").strip(" ,")
    return Canonical(f"a person {body}".strip(), style)


def action_verbs(text: str) -> str:
    """A sentence as written (lower case), but each action it names in other words said
    with its action's own verb: the phrases of ``analysis.words.PARAPHRASES`` ("puts the
    left hand up" -> "raises the left hand") and the other verbs of an action ("strolls",
    "is jogging" -> "walks", "is runs"). Subject, style, articles and word order stay, so
    that a model trained on captions as written reads what it knows around the verb."""
    low = _paraphrased(" ".join(text.lower().split()))

    def said(m: re.Match[str]) -> str:
        article, word = m.group(1), m.group(2)
        if article:   # a noun after an article stays a noun: "takes a bow", "at a trot"
            return article + _NOUN.get(word, word)
        return _CANON.get(word, word)
    return _ARTICLE_WORD.sub(said, low)


def _paraphrased(text: str) -> str:
    """``text`` (lower case) with every phrase of ``PARAPHRASES`` said with its action's
    verb and the words of its group ``keep``."""
    for pattern, action in PARAPHRASES:
        text = pattern.sub(lambda m, a=action: " ".join(
            (_VERB[a], *([m.group("keep")] if "keep" in m.re.groupindex and m.group("keep")
                         else []))), text)
    return text


#: how a sentence encoder may be given a sentence: as written, with each action's own verb
#: (:func:`action_verbs`), or in canonical form (:func:`canonical_text`)
READINGS = ("written", "verbs", "canonical")


def check_reading(reading: Any) -> None:
    """Refuse a reading that is not one of :data:`READINGS`, by name."""
    if reading not in READINGS:
        raise MotionlangError(f"reading must be one of {', '.join(READINGS)}, got {reading!r}")


def read_as(text: str, reading: str) -> str:
    """``text`` as ``reading`` (one of :data:`READINGS`) gives it to an encoder."""
    if reading == "verbs":
        return action_verbs(text)
    if reading == "canonical":
        return canonical_text(text)
    return text


def canonical_text(text: str) -> str:
    """What an encoder reads when captions are canonical: :func:`canonical`'s text, then the
    styles it names by their own names in a fixed place at the end ("a person walks
    forward, then waves left hand; style: angry"), so that a style is said one way and
    never mixed into the actions, yet a take's style can still be asked for."""
    c = canonical(text)
    named = sorted(styles_named(" ".join(c.style))) if c.style else []
    return f"{c.text}; style: {', '.join(named)}" if named else c.text

"""Descriptions checked against the body's physics, and honest about what the model does not know.

A motion-to-language model learns which words go with which features of its training
motion; on motion recorded elsewhere (another body, speed, floor, frame rate or rig) it can
name the wrong gait, or, on motion unlike anything it learnt, put out fragments. Two checks
sit between its beam and the user (:func:`describe`, what the M2L family registers as its
describer):

1. **Gait** (``features.gait``): when the feet show walking, running or jumping and the
   model's first sentence names another of the three (or says the body stands still), the
   beam is searched again with the contradicting words banned (a walk that the model calls a run is described without the
   words of running: "a woman walks straight ahead"); for a jump that the model does not
   name, or a gait for which its beam has no sentence with a verb, with its first sentence's
   subject followed by the gait's verb as a forced start ("a person jumps ..."). The rest of
   the sentence (direction, manner) is still the model's.
   Motions whose feet show none of the three (gestures, dances, standing) keep the model's
   own sentences.
2. **Familiarity**: sentences without a verb are dropped; when none is left, or the first
   sentence is so unlikely under the model that it is guessing (mean log probability per word
   below ``UNFAMILIAR_LOGP``), the first line is :data:`UNFAMILIAR` and the model's remaining
   sentences follow as the closest it has.
3. **What the body does** (``motionlang.analysis``, :func:`reconcile`): the model's first
   sentence stays first only where the actions it names agree with the main action the
   analysis finds (or the analysis finds none), it says nothing of the path that the
   travel contradicts (a circle, backwards), the model is not guessing (mean log
   probability per word of at least ``LEAD_LOGP``) and the motion is like its training
   motion (:func:`familiarity` at most ``FAMILIAR_RMS``). Otherwise the grounded sentence
   comes first (its score NaN: no model gave it) and the model's follow as alternatives.
   Style and mood words stay only where the model knows the motion well (``STYLE_RMS``)
   and is confident (``STYLE_LOGP``); the person's gender ("a woman", "his") never does
   (the training captions drew it by chance);
   sentences that repeat themselves or are broken English ("a walks", "jumps bows":
   ``analysis.garbled``) are left out.
"""
from __future__ import annotations

import re
from typing import Any

import numpy as np

from motionlang.analysis import (
    CANNOT_TELL,
    Analysis,
    analyse_positions,
    garbled,
    repeats,
    tidy,
)
from motionlang.analysis.check import contradicted
from motionlang.analysis.words import actions_named, agrees
from motionlang.datasets.bandai_text import styles_named
from motionlang.datasets.canonical import without_style
from motionlang.datasets.pos_tags import tag
from motionlang.errors import MotionlangError
from motionlang.features.body21 import normalise21
from motionlang.features.frames import motion_frames
from motionlang.features.gait import gait
from motionlang.features.joint_map import positions21
from motionlang.models.seq2seq.decode.codec import normalize
from motionlang.models.seq2seq.decode.search import _features_of, describe_features

#: what :func:`describe` says of a motion the model cannot describe
UNFAMILIAR = "the person makes an unfamiliar movement"
#: mean log probability per word (end of sentence included) below which the model is guessing:
#: far below what the packaged models give the sentences of any real motion they describe
#: with words (docs/results/real-motion.md has the measured ranges)
UNFAMILIAR_LOGP = -6.0
#: mean log probability per word at or above which the model may name a style or mood: the
#: level its first sentences reach on its own held-out training motion and seldom elsewhere
#: (docs/results/grounded-describe.md has the measured ranges)
STYLE_LOGP = -0.6
#: root mean square of the model's normalised input features (1 on its training motion):
#: above ``FAMILIAR_RMS`` the motion is unlike what the model learnt from, and its sentence
#: does not lead unless nothing else can be said; above ``STYLE_RMS`` it may not name a style
FAMILIAR_RMS = 2.5
STYLE_RMS = 1.2
#: mean log probability per word below which the model's sentence does not lead: far below
#: its sentences of motion it knows, where a forced verb left it stumbling ("jumps the way")
LEAD_LOGP = -1.5

#: a person's gender as captions name it, and the words that say no more than a person: no
#: motion shows it (the Bandai captions the models learnt from drew it by chance)
GENDERED = {"woman": "person", "man": "person", "women": "people", "men": "people",
            "lady": "person", "gentleman": "person", "girl": "person", "boy": "person",
            "guy": "person", "female": "person", "male": "person", "his": "their",
            "her": "their"}

#: "in an old man is way": the training captions' "man's", read as "man is"
_POSSESSIVE = re.compile(r"\b(man|woman|person|child|kid|lady|performer|actor) is "
                         r"(way|manner|gait|style)\b")

#: the words that name each gait, in every form a caption uses
GAIT_WORDS: dict[str, frozenset[str]] = {
    "walk": frozenset("walk walks walking walked stroll strolls strolling march marches "
                      "marching".split()),
    "run": frozenset("run runs running ran jog jogs jogging dash dashes dashing sprint "
                     "sprints sprinting".split()),
    "jump": frozenset("jump jumps jumping jumped hop hops hopping leap leaps leaping".split()),
    # not a gait, but what contradicts one: "the subject is standing still" of a walk
    "stand": frozenset("stand stands standing still".split()),
}
#: the form of each gait's verb forced after the subject when the model does not name it
GAIT_VERB = {"walk": "walks", "run": "runs", "jump": "jumps"}


def named_gait(text: str) -> str | None:
    """The gait a sentence names first (by word order), or None."""
    for word in text.lower().split():
        for g, words in GAIT_WORDS.items():
            if word in words:
                return g
    return None


def has_verb(text: str) -> bool:
    """Whether a sentence has a verb: one the tagger (``datasets.pos_tags``) knows, a gait
    word, or a third-person form right after the subject, adverbs aside ("a man beckons", "a
    stage actor sprints", "a woman hesitantly shows": the tagger's lexicon is small and reads
    such words as plural nouns)."""
    if named_gait(text) is not None:
        return True
    words, tags = text.lower().split(), [t.rsplit("/", 1)[1] for t in tag(text)]
    if len(tags) != len(words):
        return any(t == "VERB" for t in tags)
    for i, (w, t) in enumerate(zip(words, tags)):
        if t == "VERB":
            return True
        before = [x for x in tags[:i] if x != "ADV"]      # "a woman hesitantly shows"
        if (before and t == "NOUN" and before[-1] in ("NOUN", "PRON") and w.endswith("s")
                and not w.endswith("ss")):
            return True
    return False


def _subject(text: str) -> list[str]:
    """The words before a sentence's first verb ("a stage actor" of "a stage actor bows")."""
    words = text.split()
    tags = tag(text)
    if len(tags) != len(words):
        return []
    for i, t in enumerate(tags):
        if t.endswith("/VERB") or named_gait(words[i]):
            return words[:i]
    return []


def ground(model: Any, frames, hyps: list[tuple[str, float]], action: str | None, *,
           width: int, **beam: Any) -> list[tuple[str, float]]:
    """The beam ``hyps`` of ``frames`` (T, F), searched again where its first sentence
    contradicts the gait ``action`` ("walk", "run", "jump" or None; module docstring)."""
    if action is None or not hyps:
        return hyps
    said = named_gait(hyps[0][0])
    if said == action:
        return hyps
    if action != "jump":
        if said is not None:    # another gait named: search again without its words
            again = describe_features(model, frames, width=width,
                                      banned_words=_others(action), **beam)
            if again and has_verb(again[0][0]):
                return again
        elif has_verb(hyps[0][0]):
            return hyps         # something else named over the gait (a wave while walking)
    # a jump the model does not name, or a gait it has no sentence for: force the verb
    # "a person is" + "jumps" would be no English: the subject without its auxiliary
    subject = [w for w in _subject(hyps[0][0]) if w not in ("is", "are")] or ["a", "person"]
    prefix = [*subject, GAIT_VERB[action]]
    if all(w in getattr(model.vocab, "stoi", {}) for w in prefix):
        return describe_features(model, frames, width=max(width, 2), prefix=prefix,
                                 banned_words=_others(action), **beam)[:width]
    return hyps


def _others(action: str) -> list[str]:
    """The words of every gait but ``action`` (and of standing still)."""
    return [w for g, ws in GAIT_WORDS.items() if g != action for w in ws]


def familiar(hyps: list[tuple[str, float]]) -> list[tuple[str, float]]:
    """The beam without its verbless sentences, led by :data:`UNFAMILIAR` when nothing is
    left or the first sentence is a guess (module docstring)."""
    kept = [(t, s) for t, s in hyps if t.strip() and has_verb(t)]
    if not kept:
        return [(UNFAMILIAR, hyps[0][1] if hyps else float("-inf"))]
    first_text, first_score = kept[0]
    if first_score / (len(first_text.split()) + 1) < UNFAMILIAR_LOGP:
        return [(UNFAMILIAR, first_score)] + kept
    return kept


def describe(model: Any, motion, *, width: int, length_penalty: float, rank: str,
             max_len: int | None = None, grounded: bool = True) -> list[tuple[str, float]]:
    """A :class:`Motion` -> up to W sentences with their total log probability, best first
    (as ``models.seq2seq.decode.search.describe``), checked against the motion's gait and
    the model's familiarity with it (module docstring); ``grounded=False``: the model's beam
    as it is. The family's describer (``Family.describes``): ``width``, ``length_penalty``
    and ``rank`` come from the caller's ``library.options.DescribeOptions``."""
    frames = motion_frames(_features_of(model), motion, 1)[0]
    beam: dict[str, Any] = dict(max_len=max_len, length_penalty=length_penalty, rank=rank)
    hyps = describe_features(model, frames, width=width, **beam)
    if not grounded:
        return hyps
    body = normalise21(positions21(motion))
    action = gait(body, motion.fps).action if len(body) > 1 else None
    checked = familiar(ground(model, frames, hyps, action, width=width, **beam))
    try:
        analysis: Analysis | None = analyse_positions(body, motion.fps)
    except MotionlangError:
        analysis = None
    return reconcile(checked, analysis, familiarity(model, frames))[:max(width, 1)]


def familiarity(model: Any, frames) -> float:
    """Root mean square of ``frames`` (T, F) after the model's own normaliser: near 1 on
    motion like its training motion, larger the further a motion lies outside it."""
    x = normalize(model.normalizer, frames)
    return float(np.sqrt(np.mean(np.square(x)))) if np.size(x) else float("inf")




def ungendered(text: str) -> str:
    """``text`` with the person it names neither a woman nor a man (:data:`GENDERED`):
    "a woman walks forward and raises her hand" -> "a person walks forward and raises
    their hand"."""
    words = text.split()
    return " ".join(GENDERED.get(w.lower(), w) for w in words) if any(
        w.lower() in GENDERED for w in words) else text


def per_word(text: str, score: float) -> float:
    """Mean log probability per word, the end of the sentence counted."""
    return score / (len(text.split()) + 1)


def reconcile(hyps: list[tuple[str, float]], analysis: Analysis | None,
              rms: float = 1.0) -> list[tuple[str, float]]:
    """The checked beam ``hyps`` against what the body does (module docstring, 3), ``rms``
    the model's :func:`familiarity` with the motion: the model's first sentence kept, or the
    grounded sentence (score NaN) put first; style words only where the model knows the
    motion well and is confident."""
    out = []
    for t, s in hyps:
        knows = rms <= STYLE_RMS and per_word(t, s) >= STYLE_LOGP
        if t != UNFAMILIAR and styles_named(t) and not knows:
            t = without_style(t)
            if styles_named(t) or not has_verb(t):
                continue
        # a woman, a man: its training captions drew them by chance (``bandai_text``
        # NEUTRAL), so that no motion, not even its own, shows which
        t = tidy(_POSSESSIVE.sub(r"\1's \2", ungendered(t)))
        # "3 squats 3 times squats", "a person jumps bows": the model stumbling
        if not repeats(t) and not garbled(t):
            out.append((t, s))
    hyps = list({t: (t, s) for t, s in reversed(out)}.values())[::-1]   # each once
    if analysis is None:   # one frame, no body: what the model says of it rests on nothing
        return [(CANNOT_TELL, float("nan"))] + [(t, s) for t, s in hyps if t != UNFAMILIAR]
    grounded = analysis.sentence()
    if not hyps:
        return [(grounded, float("nan"))]
    first, first_score = hyps[0]
    main = analysis.main_action()
    # standing still is no opinion: a gesture too small for the detectors is still made
    agree = (main in (None, "stand") or agrees(actions_named(first), main)) and \
        not contradicted(first, analysis)
    sure = per_word(first, first_score) >= LEAD_LOGP
    others = [(t, s) for t, s in hyps if t != grounded]   # the same sentence said once
    if first != UNFAMILIAR and agree and sure and (rms <= FAMILIAR_RMS or main is None):
        return hyps if len(others) < len(hyps) else hyps + [(grounded, float("nan"))]
    return [(grounded, float("nan"))] + [(t, s) for t, s in others if t != UNFAMILIAR]

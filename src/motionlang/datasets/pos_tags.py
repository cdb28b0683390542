"""A small offline part-of-speech tagger for motion descriptions: ``lemma/POS`` tokens in
the universal tag set, as HumanML3D's ``texts/ID.txt`` carry them (the public release tags
with spaCy, which needs a model download; NLTK's taggers need downloads too).

Lexicons of closed-class words and motion verbs plus suffix rules give VERB, NOUN, ADJ, ADV,
DET, ADP, PRON, AUX, NUM, CCONJ, SCONJ and PART, and a rough lemma (``walks``, ``walking``,
``walked`` -> ``walk``). Used by the HumanML3D writer (``datasets.humanml3d_export``) and the
text-motion evaluator (``models.evaluator.text``) for captions without tags.
"""
from __future__ import annotations

from motionlang.datasets.text import tokenize

# The rule tagger's lexicons (lower-case surface forms).
_CLOSED = {tag: set(words.split()) for tag, words in {
    "DET": "a an the this that these those each every some any another both all no either",
    "ADP": "in on at to from with by of for into onto over under around across through "
           "towards toward off about behind above below along after before like between "
           "near against upon during without beside via",
    "PRON": "he she it they them his her their its him himself herself themselves itself "
            "someone something somebody i you we us our one's",
    "AUX": "is are was were be been being has have had does do did will would can could "
           "should may might must am",
    "CCONJ": "and or but nor then", "SCONJ": "while as if until because when whilst",
    "PART": "not", "NUM": "one two three four five six seven eight nine ten eleven twelve "
                          "twenty thirty hundred once twice half"}.items()}
_ADV = set("again away back forward forwards backward backwards around sideways together "
           "then still also very too quite almost slightly repeatedly up down out".split())
_ADJ = set("left right clockwise counterclockwise anticlockwise small big large high low "
           "wide narrow other same quick slow fast full straight short long little several "
           "few many entire whole".split())
_VERBS = set(("walk run jump turn raise lower wave kick step stand sit squat bend lean hop "
              "throw catch punch lift reach stretch swing move go spin rotate climb crawl jog "
              "kneel dance clap push pull pick put place hold shake nod bow look stop start "
              "begin continue take make use open close grab touch carry drop rub wash stumble "
              "balance flap shuffle spread stroll bring cross fall slide skip march circle "
              "roll twist perform do").split())
#: irregular past forms of motion verbs -> lemma
_IRREGULAR = dict(pair.split(":") for pair in (
    "sat:sit stood:stand ran:run went:go threw:throw took:take held:hold fell:fall "
    "caught:catch spun:spin swung:swing knelt:kneel made:make brought:bring began:begin "
    "got:get came:come").split())
#: pronouns before a noun: the next word is tagged as after a determiner
_POSSESSIVE = set("his her their its our your my".split())


def _lemma(word: str, pos: str) -> str:
    """A rough lemma of a verb or noun (suffix rules, checked against the verb lexicon)."""
    if pos == "VERB":
        if word in _IRREGULAR:
            return _IRREGULAR[word]
        for suffix in ("ing", "ed", "es", "s"):
            if word.endswith(suffix) and len(word) > len(suffix) + 2:
                stem = word[:-len(suffix)]
                for cand in (stem, stem + "e", stem[:-1] if stem[-1:] == stem[-2:-1] else None,
                             stem[:-1] + "y" if stem.endswith("i") else None):
                    if cand and cand in _VERBS:
                        return cand
                if suffix in ("es", "s") and word.endswith("ss"):
                    return word
                return stem if suffix != "s" else word[:-1]
    if pos == "NOUN" and word.endswith("s") and not word.endswith("ss") and len(word) > 3:
        return word[:-2] if word.endswith(("ches", "shes", "xes")) else word[:-1]
    return word


def _open_class(word: str, prev: str | None) -> str:
    """VERB, NOUN, ADJ or ADV of a word outside the closed classes, from its form, the
    verb lexicon and the previous word's tag."""
    if word in _ADV and prev not in ("DET", "ADJ"):
        return "ADV"
    if word.endswith("ly") and len(word) > 4:
        return "ADV"
    if word in _ADJ or word.endswith(("ful", "ous", "ive", "less")):
        return "ADJ"
    if prev in ("DET", "ADJ", "NUM"):
        return "NOUN"
    if (word.endswith(("ing", "ed")) and len(word) > 4) or word in _IRREGULAR:
        return "VERB"
    if prev in ("PRON", "NOUN", "AUX", "PART", "CCONJ", "SCONJ", "ADV", None) or \
            word in _VERBS:
        base = _lemma(word, "VERB")
        if base in _VERBS or prev in ("PRON", "AUX", "PART"):
            return "VERB"
    return "NOUN"


def tag(caption: str) -> list[str]:
    """``"A man walks forward slowly."`` -> ``["a/DET", "man/NOUN", "walk/VERB",
    "forward/ADV", "slowly/ADV"]``: ``lemma/POS`` tokens of the normalised words
    (``datasets.text.tokenize``; digits tagged NUM), universal tags."""
    out: list[str] = []
    prev: str | None = None
    for word in tokenize(caption):
        word = word.lower()
        closed = next((t for t, ws in _CLOSED.items() if word in ws), None)
        pos = "NUM" if word[:1].isdigit() else closed or _open_class(word, prev)
        out.append(f"{_lemma(word, pos)}/{pos}")
        prev = "DET" if word in _POSSESSIVE else pos
    return out

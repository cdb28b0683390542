"""Words a model's vocabulary lacks, read as the nearest word it knows.

A text-to-motion model whose text side is a word vocabulary (the L2M) turns every word it
never saw in training into one unknown-word token, so "a person strolls" steers it no more
than "a person". :class:`WordMapper` reads such a word as a known one:

1. spelling corrections first: they are part of tokenising (``datasets.text.tokenize``);
2. a function word ("for", "but", "it") is never mapped: it stays unknown, as before,
   because its nearest content word would put an action into the sentence;
3. another form of a known word ("walked", "turned", "persons") is read as that word:
   the forms of one stem (:func:`stem`), the same ending first ("walking" for "strolling"
   but "walks" for "walked", the captions' tense), then the nearest by word vectors;
4. otherwise the known content word nearest by word vectors (:data:`VECTORS`: the frozen
   MiniLM sentence encoder that the two-stream and retrieval families read text with, or
   GloVe 6B 50d), if its cosine similarity reaches the floor; below it the word stays
   unknown.

The result, a :class:`WordReading`, says what was read as what, so that the caller can show
it (``motionlang generate`` prints ``read "strolls" as "walks"``). Importing it loads no
torch; the MiniLM vectors do, on the first unknown word.
"""
from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from motionlang.errors import MotionlangError

#: words that carry grammar, not an action, a body part or a manner: never mapped, and
#: never the word another is mapped to
FUNCTION_WORDS = frozenset("""
a an the this that these those it its his her their them they he she him we you i me my
your our one ones some any each every all both either neither another other such
and or but nor so yet if then than because since while when where whereas whether though
although until unless after before during as at by for from in into of off on onto out
over under up down to toward towards with within without through across along around
about above below behind beside between beyond upon via per
is are was were be been being am has have had having do does did doing done will would
shall should can could may might must not no nor very too also just only still again
there here how what which who whom whose why
""".split())

_SUFFIXES = ("ing", "ed", "es", "s", "ly")
_DOUBLED = re.compile(r"([bdgklmnprt])\1$")


def stem(word: str) -> str:
    """A crude stem shared by the forms of one English word: "walked", "walks", "walking"
    -> "walk"; "stopped" -> "stop"; "waves", "waving", "wave" -> "wav"."""
    w = word
    for suffix in _SUFFIXES:
        if w.endswith(suffix) and len(w) - len(suffix) >= 3:
            w = w[:-len(suffix)]
            break
    w = _DOUBLED.sub(r"\1", w)
    return w[:-1] if w.endswith("e") and len(w) > 3 else w


@runtime_checkable
class WordOptions(Protocol):
    """The sampling option of every family whose text side is a word vocabulary: its
    ``Options`` dataclass has a field ``map_words: bool = True`` (``--model
    l2m:map_words=false``), and the text-to-motion adapter reads sentences through
    :class:`WordMapper` while it is on (off: each unknown word is one unknown-word token).
    """

    map_words: bool


@runtime_checkable
class ReadingOptions(Protocol):
    """The sampling option of a family that reads sentences with a pretrained encoder: its
    ``Options`` dataclass has a field ``reading: str`` (``--model masked:reading=verbs``),
    how a sentence is given to the encoder (``datasets.canonical.read_as``: ``written``,
    ``verbs``, ``canonical``)."""

    reading: str


def _word_class(word: str) -> str:
    return "ly" if word.endswith("ly") else "ing" if word.endswith("ing") else ""


def _form_rank(word: str, form: str) -> int:
    """2: the same ending ("walking" for "strolling"); 1: the captions' present tense for a
    past one ("walks" for "walked"); 0: another form."""
    ending = next((s for s in _SUFFIXES if word.endswith(s)), "")
    if ending and form.endswith(ending):
        return 2
    return int(ending == "ed" and form.endswith("s"))


class WordsRead(UserWarning):
    """Issued when unknown words of a sentence were read as known ones (its message is
    :meth:`WordReading.message`); the command line prints it as a note, not a warning."""


@dataclass(frozen=True)
class WordReading:
    """How a model reads one sentence.

    Attributes:
        text: the sentence as the model reads it: the input itself when nothing was mapped,
            else its tokens with each mapped word replaced.
        mapped: ``(word, known word, cosine similarity)`` for each mapped word, in order of
            appearance (similarity 1.0 for another form of a known word).
        unknown: the words still unknown (function words, and words below the floor).
    """

    text: str
    mapped: tuple[tuple[str, str, float], ...] = ()
    unknown: tuple[str, ...] = ()

    def message(self) -> str:
        """``read "strolls" as "walks", "jab" as "punches"``; "" when nothing was mapped."""
        if not self.mapped:
            return ""
        return "read " + ", ".join(f'"{w}" as "{k}"' for w, k, _ in self.mapped)

    def as_dict(self) -> dict[str, object]:
        """JSON-ready: ``{"text", "mapped": {word: known word}, "unknown": [...]}``."""
        return {"text": self.text, "mapped": {w: k for w, k, _ in self.mapped},
                "unknown": list(self.unknown)}


class GloveVectors:
    """Unit GloVe vectors with the common mean and the top ``n_removed`` principal directions
    of the ``n_common`` most frequent words taken out: raw GloVe cosines are dominated by
    those directions (word frequency), which makes every frequent word look alike (Mu and
    Viswanath 2018, "all-but-the-top")."""

    def __init__(self, n_common: int = 50_000, n_removed: int = 2):
        from motionlang.models.text_tokens import glove_table
        self.index, self._raw = glove_table()
        common = np.asarray(self._raw[:n_common], dtype=np.float64)
        self.mean = common.mean(axis=0)
        self.removed = np.linalg.svd(common - self.mean, full_matrices=False)[2][:n_removed]

    def __contains__(self, word: str) -> bool:
        return word in self.index

    def unit(self, words: Sequence[str]) -> np.ndarray:
        """(len(words), 50) float64 unit vectors of words that GloVe has (KeyError else)."""
        v = np.asarray(self._raw[[self.index[w] for w in words]], dtype=np.float64) - self.mean
        v = v - (v @ self.removed.T) @ self.removed
        return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-12)


class MiniLMVectors:
    """A word as the MiniLM sentence encoder sees it alone: its last layer's states averaged
    over the word's tokens (the encoder's own pooling), unit length. Any word has one (word
    pieces), and a pretrained sentence encoder places synonyms closer than 50-d GloVe does
    ("rapidly" by "quickly", not by its opposite "slowly")."""

    def __init__(self) -> None:
        from motionlang.models.text_tokens import TransformerTokens
        self._tokens = TransformerTokens("minilm", layers=(6,))

    def __contains__(self, word: str) -> bool:
        return True

    def unit(self, words: Sequence[str]) -> np.ndarray:
        """(len(words), 384) float64 unit vectors."""
        v = np.stack([f.mean(dim=0).double().numpy() for f in self._tokens.many(list(words))])
        return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-12)


#: the word vectors :class:`WordMapper` can compare by, and the least cosine similarity at
#: which an unknown word is read as its nearest known word in each: below it, words of
#: another sense pass (a body part for another body part, a manner for its opposite)
VECTORS: dict[str, tuple[type, float]] = {"minilm": (MiniLMVectors, 0.6),
                                          "glove": (GloveVectors, 0.65)}


@functools.cache
def word_vectors(name: str = "minilm") -> Any:
    """The process's vectors of :data:`VECTORS` ``name`` (built once, on first use)."""
    if name not in VECTORS:
        raise MotionlangError(f"word vectors {name!r}: expected one of {', '.join(VECTORS)}")
    return VECTORS[name][0]()


class WordMapper:
    """Reads sentences with a fixed vocabulary, unknown words mapped to known ones.

    Args:
        known: the vocabulary's words (special tokens such as ``<unk>`` are ignored).
        vectors: a name of :data:`VECTORS` (read on first need) or an object with
            ``__contains__(word)`` and ``unit(words) -> (N, D)`` unit vectors.
        floor: least similarity of an embedding match (default: that of ``vectors`` in
            :data:`VECTORS`; required for an object).
    """

    def __init__(self, known: Iterable[str], *, vectors: Any = "minilm",
                 floor: float | None = None):
        self.known = frozenset(w for w in known if not w.startswith("<"))
        if floor is None and not isinstance(vectors, str):
            raise MotionlangError("word vectors given as an object need a floor")
        self.floor = float(VECTORS[vectors][1] if floor is None else floor)
        self._vectors = vectors
        self._targets: tuple[list[str], np.ndarray] | None = None
        self._stems: dict[str, list[str]] = {}
        for w in sorted(self.known - FUNCTION_WORDS):
            self._stems.setdefault(stem(w), []).append(w)

    @classmethod
    def of_vocabulary(cls, vocab: Any, **kw: Any) -> WordMapper:
        """The mapper of a model's vocabulary (a ``datasets.text.Vocabulary`` or a list of
        words); one that maps nothing for a model without one."""
        words = getattr(vocab, "itos", vocab)
        if words is None or isinstance(words, str) or not hasattr(words, "__iter__"):
            words = ()
        return cls(words, **kw)

    @property
    def vectors(self) -> Any:
        if isinstance(self._vectors, str):
            self._vectors = word_vectors(self._vectors)
        return self._vectors

    def _target_vectors(self) -> tuple[list[str], np.ndarray]:
        if self._targets is None:
            words = sorted(w for w in self.known - FUNCTION_WORDS if w in self.vectors)
            self._targets = (words, self.vectors.unit(words) if words else np.zeros((0, 1)))
        return self._targets

    def _similarity(self, word: str, candidates: Sequence[str]) -> np.ndarray:
        if word not in self.vectors:
            return np.zeros(len(candidates))
        have = [c for c in candidates if c in self.vectors]
        sims = dict(zip(have, self.vectors.unit(have) @ self.vectors.unit([word])[0]))
        return np.array([sims.get(c, 0.0) for c in candidates])

    def nearest(self, word: str) -> tuple[str, float] | None:
        """The known word ``word`` is read as and its similarity, or None (stays unknown).
        A known word is read as itself."""
        if word in self.known:
            return word, 1.0
        if word in FUNCTION_WORDS or not word.isalpha():
            return None
        forms = self._stems.get(stem(word))
        if forms:   # another form of a known word: the same ending first, then the meaning
            sims = self._similarity(word, forms)
            return max(zip(forms, sims), key=lambda f: (_form_rank(word, f[0]), f[1]))[0], 1.0
        if word not in self.vectors:
            return None
        words, vecs = self._target_vectors()
        if not words:
            return None
        sims = vecs @ self.vectors.unit([word])[0]
        # an adverb for an adverb, a participle for a participle: across those classes the
        # nearest word often shares only a topic ("kneels" and "daintily")
        sims[[_word_class(w) != _word_class(word) for w in words]] = -1.0
        best = int(np.argmax(sims))
        return (words[best], float(sims[best])) if sims[best] >= self.floor else None

    def read(self, tokens: Sequence[str], text: str) -> WordReading:
        """The reading of a sentence ``text`` whose tokens (``datasets.text.tokenize``) are
        ``tokens``: ``text`` itself when every word is known or none maps."""
        seen: dict[str, tuple[str, float] | None] = {}
        for t in tokens:
            if t not in seen:
                seen[t] = self.nearest(t)
        mapped = tuple((w, *hit) for w, hit in seen.items()
                       if hit is not None and w not in self.known)
        unknown = tuple(w for w, hit in seen.items() if hit is None)
        if not mapped:
            return WordReading(text, (), unknown)
        as_known = {w: k for w, k, _ in mapped}
        return WordReading(" ".join(as_known.get(t, t) for t in tokens), mapped, unknown)

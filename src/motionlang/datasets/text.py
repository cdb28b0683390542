"""Text processing for motion descriptions: normalisation, tokens and a vocabulary.

``normalize`` reproduces the normalised column of the KIT-ML sentence list
(``sentences_corrections.tsv``, kit-mld-ke): lower case, punctuation removed, contractions
expanded, "°" spelled "degrees", number words written as digits and misspellings corrected.
The word-level corrections come from a table shipped with the package
(``motionlang/data/spelling_corrections.tsv``), derived from that sentence list by
``scripts/derive_spelling_table.py``.
"""
from __future__ import annotations

import functools
import json
import re
from collections import Counter
from collections.abc import Iterable, Sequence
from importlib import resources
from pathlib import Path

from motionlang.errors import DatasetError, MotionlangError
from motionlang.utils import limits
from motionlang.utils.atomic import atomic_write
from motionlang.utils.sidecar import load_json

#: control characters: never part of a word
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def _check_size(words: int, what: str) -> None:
    """Refuse a vocabulary beyond ``max_vocabulary`` words: its embedding and softmax
    matrices grow with it (a million words of 512 units is 2 GB per matrix)."""
    msg = limits.message("max_vocabulary", words, "the vocabulary size")
    if msg:
        raise DatasetError(f"{what}: {msg}")

PAD, SOS, EOS, UNK = "<pad>", "<sos>", "<eos>", "<unk>"
SPECIALS = (PAD, SOS, EOS, UNK)  # ids 0, 1, 2, 3

# Contractions are expanded before punctuation is dropped, as in the reference column
# ("don't" -> "do not", "it's" -> "it is").
_CONTRACTIONS = [
    (re.compile(r"\bcan[’']t\b"), "can not"),
    (re.compile(r"\bwon[’']t\b"), "will not"),
    (re.compile(r"n[’']t\b"), " not"),
    (re.compile(r"[’']s\b"), " is"),
    (re.compile(r"[’']re\b"), " are"),
    (re.compile(r"[’']m\b"), " am"),
    (re.compile(r"[’']ll\b"), " will"),
    (re.compile(r"[’']ve\b"), " have"),
]
# "T-pose", "S-shape": a single letter naming a shape keeps its hyphen and capital.
_LETTER_SHAPE = re.compile(r"(?<![a-z0-9-])([a-z])-([a-z]+)")
# Tokens: a shape word, a decimal number ("3,5" is kept as written), a number, a word.
# Digits and letters are split ("1m" -> "1 m"); everything else is a separator.
_TOKEN = re.compile(r"[A-Z]-[a-z]+|\d+(?:,\d+)?|[a-z]+")

CORRECTIONS_RESOURCE = "spelling_corrections.tsv"


@functools.lru_cache(maxsize=1)
def spelling_corrections() -> dict[str, str]:
    """The shipped word table: lower-case token -> replacement (zero or more words)."""
    text = resources.files("motionlang").joinpath("data", CORRECTIONS_RESOURCE).read_text(
        encoding="utf-8")
    return parse_corrections(text)


def parse_corrections(text: str, source: str = CORRECTIONS_RESOURCE) -> dict[str, str]:
    """Parse a ``wrong<TAB>right`` table (``#`` comments allowed) into a dict."""
    table: dict[str, str] = {}
    for lineno, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        parts = line.split("\t")
        if len(parts) != 2:
            raise DatasetError(f"{source}:{lineno}: expected 'wrong<TAB>right', got {line!r}")
        table[parts[0]] = parts[1]
    return table


def base_tokens(sentence: str) -> list[str]:
    """Tokens after case folding and punctuation removal, before spelling corrections."""
    s = sentence.replace("°", " degrees ")
    s = s.lower()
    for pattern, repl in _CONTRACTIONS:
        s = pattern.sub(repl, s)
    s = _LETTER_SHAPE.sub(lambda m: f"{m.group(1).upper()}-{m.group(2)}", s)
    return _TOKEN.findall(s)


def normalize(sentence: str, corrections: dict[str, str] | None = None) -> str:
    """Normalise one sentence: ``"A person walks five steps." -> "a person walks 5 steps"``.

    Args:
        sentence: raw annotation text.
        corrections: word table to apply (default: the shipped KIT-ML table; ``{}`` for none).
    """
    table = spelling_corrections() if corrections is None else corrections
    out = []
    for tok in base_tokens(sentence):
        rep = table.get(tok, tok)
        if rep:
            out.append(rep)
    return " ".join(" ".join(out).split())


def tokenize(sentence: str) -> list[str]:
    """Normalise and split on whitespace."""
    return normalize(sentence).split()


class Vocabulary:
    """Word <-> id map with ``<pad>=0, <sos>=1, <eos>=2, <unk>=3``.

    Example::

        vocab = Vocabulary.build(["a person walks", "a person runs"], min_count=1)
        ids = vocab.encode("a person walks")    # [1, ..., 2] with SOS/EOS
        vocab.decode(ids) == "a person walks"
    """

    def __init__(self, words: Iterable[str] = ()):
        self.itos: list[str] = list(SPECIALS)
        self.stoi: dict[str, int] = {w: i for i, w in enumerate(self.itos)}
        for w in words:
            self.add(w)

    pad_id, sos_id, eos_id, unk_id = 0, 1, 2, 3

    def add(self, word: str) -> int:
        if word not in self.stoi:
            self.stoi[word] = len(self.itos)
            self.itos.append(word)
        return self.stoi[word]

    def __len__(self) -> int:
        return len(self.itos)

    def __contains__(self, word: str) -> bool:
        return word in self.stoi

    @classmethod
    def build(cls, sentences: Iterable[str], min_count: int = 1) -> Vocabulary:
        """Words seen at least ``min_count`` times (after ``tokenize``), most frequent first,
        ties in alphabetical order so that the ids do not depend on the input order."""
        counts = Counter(tok for s in sentences for tok in tokenize(s))
        words = sorted((w for w, c in counts.items() if c >= min_count),
                       key=lambda w: (-counts[w], w))
        _check_size(len(words), f"the sentences hold {len(words):,} distinct words seen at "
                                f"least {min_count} times (raise min_count)")
        return cls(w for w in words if w not in SPECIALS)

    def encode(self, sentence: str | Sequence[str], *, add_sos_eos: bool = True,
               normalise: bool = True) -> list[int]:
        """Ids of a sentence (a string is tokenised; a list of tokens is used as is)."""
        toks = (tokenize(sentence) if normalise else sentence.split()) \
            if isinstance(sentence, str) else list(sentence)
        ids = [self.stoi.get(t, self.unk_id) for t in toks]
        return [self.sos_id, *ids, self.eos_id] if add_sos_eos else ids

    def decode(self, ids: Iterable[int], *, strip_special: bool = True) -> str:
        """Words of ``ids``; stops at the first EOS and drops PAD/SOS when ``strip_special``."""
        words = []
        for i in ids:
            i = int(i)
            if strip_special:
                if i == self.eos_id:
                    break
                if i in (self.pad_id, self.sos_id):
                    continue
            words.append(self.itos[i] if 0 <= i < len(self.itos) else UNK)
        return " ".join(words)

    def to_dict(self) -> dict:
        """``{"specials", "itos"}``, JSON-ready (saved inside model checkpoints)."""
        return {"specials": list(SPECIALS), "itos": self.itos}

    @classmethod
    def from_dict(cls, d: dict) -> Vocabulary:
        """Inverse of :meth:`to_dict`; DatasetError on a malformed entry."""
        itos = d.get("itos") if isinstance(d, dict) else None
        if not isinstance(itos, list) or list(itos[:4]) != list(SPECIALS):
            raise DatasetError("vocabulary: 'itos' must be a list starting with "
                               f"{list(SPECIALS)}")
        _check_size(len(itos), f"vocabulary: {len(itos):,} words")
        for w in itos:
            if not isinstance(w, str) or not w or _CONTROL.search(w):
                raise DatasetError(f"vocabulary: the word {w!r} is not a word (empty, not "
                                   "text, or with control characters)")
        return cls(itos[4:])

    def save(self, path: str | Path) -> None:
        """Write :meth:`to_dict` as JSON (atomically)."""
        with atomic_write(path) as fh:
            json.dump(self.to_dict(), fh, indent=0)

    @classmethod
    def load(cls, path: str | Path) -> Vocabulary:
        """Read a file written by :meth:`save`."""
        try:
            d = load_json(path, "vocabulary")
        except MotionlangError as exc:
            raise DatasetError(str(exc)) from None
        try:
            return cls.from_dict(d)
        except DatasetError as exc:
            raise DatasetError(f"{path}: {exc}") from None

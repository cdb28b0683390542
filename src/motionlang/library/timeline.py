"""A long take as a timeline: the sentences of overlapping windows merged where neighbours
say the same thing.

Each window (:mod:`.windows`) is described on its own; its first sentence is its label. Time
is shared out between overlapping windows at the midpoints of their centres (each instant
belongs to the window centred nearest to it), so the segments tile the take without
overlapping. Neighbouring windows whose labels agree become one segment. They agree by
``merge``:

* ``"sentence"``: the same first sentence (compared by its words, case and punctuation
  aside);
* ``"action"``: the same action, read from the sentence: the lemma of its main verb (the first
  word the part-of-speech tagger ``datasets.pos_tags`` marks as a verb, not right after a
  preposition or article, light verbs such as "does" or "takes" passed over), else of its first noun that is not the person ("does 3
  jumps", "3 jumps": jump), with the side or direction words the sentence names (left,
  right, both, back). "a person walks forward" and "a man walks slowly" agree; "waves with
  the left hand" and "waves with the right hand" do not.

A run of one window (``bridge``) between two runs that agree is taken for a flicker of the
describer, not an action, and joins them. A segment's sentence is the label most of its
windows gave (ties: the higher score), and its score is that label's mean score over the
windows that gave it.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from motionlang.datasets.pos_tags import tag
from motionlang.datasets.text import base_tokens
from motionlang.errors import MotionlangError
from motionlang.library.options import MERGES
from motionlang.library.windows import Window

#: verbs that name no action of their own: the action is their object ("does 3 jumps")
_LIGHT = set("do perform make take start begin continue keep try".split())
#: who moves, never the action ("3 jumps" has no verb: its first other noun is the action)
_PEOPLE = set("person man woman human someone figure guy lady boy girl subject actor "
              "character people".split())
#: words that tell one action from another of the same verb
_SIDES = {"left": "left", "right": "right", "both": "both", "back": "back",
          "backward": "back", "backwards": "back"}


@dataclass(frozen=True)
class Segment:
    """``start`` to ``end`` seconds of a take, described by ``text`` with its ``score``
    (the describer's: log P of a beam, cosine of a bank sentence), over ``windows``
    windows."""

    start: float
    end: float
    text: str
    score: float
    windows: int = 1

    def line(self) -> str:
        """``0.0-4.0 s  a person walks forward``"""
        return f"{self.start:.1f}-{self.end:.1f} s  {self.text}"


def action_of(sentence: str) -> str:
    """The action a sentence names (module docstring): ``"walk"``, ``"wave left"``."""
    words = [t.rsplit("/", 1) for t in tag(sentence)]
    after = ["", *(pos for _, pos in words)]   # a "verb" after "in" or "the" is a noun
    head = next((w for (w, pos), prev in zip(words, after) if pos == "VERB"
                 and w not in _LIGHT and prev not in ("ADP", "DET")), None) or \
        next((w for w, pos in words if pos == "NOUN" and w not in _PEOPLE), None)
    if head is None:
        return " ".join(w for w, _ in words)
    sides = dict.fromkeys(_SIDES[w] for w in base_tokens(sentence) if w in _SIDES)
    return " ".join([head, *sides])


def merge_key(sentence: str, merge: str) -> str:
    """What two labels must share to be merged (``merge``: one of :data:`MERGES`)."""
    if merge == "sentence":
        return " ".join(base_tokens(sentence))
    if merge == "action":
        return action_of(sentence)
    raise MotionlangError(f"merge must be one of {', '.join(MERGES)}, got {merge!r}")


def _shares(spans: Sequence[Window], end: float) -> list[tuple[float, float]]:
    """The part of the take each window owns: from the midpoint of its centre and its
    predecessor's to the midpoint with its successor's (the first from 0, the last to
    ``end``)."""
    centres = [(w.start + w.end) / 2 for w in spans]
    cuts = [(a + b) / 2 for a, b in zip(centres, centres[1:])]
    return list(zip([0.0, *cuts], [*cuts, end]))


def _runs(keys: Sequence[str], bridge: int) -> list[tuple[str, int, int]]:
    """``(key, first, stop)`` runs of equal neighbouring keys; a run of at most ``bridge``
    windows between two runs of one key joins them."""
    runs: list[tuple[str, int, int]] = []
    for i, key in enumerate(keys):
        if runs and runs[-1][0] == key:
            runs[-1] = (key, runs[-1][1], i + 1)
        elif len(runs) >= 2 and runs[-2][0] == key and runs[-1][2] - runs[-1][1] <= bridge:
            runs[-2:] = [(key, runs[-2][1], i + 1)]
        else:
            runs.append((key, i, i + 1))
    return runs


def _segment(start: float, end: float, labels: Sequence[tuple[str, float]]) -> Segment:
    said: dict[str, list[float]] = {}
    for text, score in labels:
        said.setdefault(text, []).append(score)
    text = max(said, key=lambda t: (len(said[t]), max(said[t])))
    return Segment(round(start, 3), round(end, 3), text, sum(said[text]) / len(said[text]))


def merge_windows(spans: Sequence[Window], labels: Sequence[tuple[str, float]], *,
                  end: float | None = None, merge: str = "action",
                  bridge: int = 1) -> list[Segment]:
    """Segments of a take from its windows (in time order) and each one's label
    ``(sentence, score)``; ``end``: the take's length in seconds (default the last
    window's end); ``bridge``: a run of at most this many windows between two runs that
    agree is a flicker of the describer, and the three become one segment (0: none is)."""
    if len(spans) != len(labels):
        raise MotionlangError(f"{len(spans)} windows but {len(labels)} labels")
    if not spans:
        return []
    shares = _shares(spans, spans[-1].end if end is None else end)
    keys = [merge_key(text, merge) for text, _ in labels]
    out = []
    for key, first, stop in _runs(keys, bridge):
        agree = [lab for lab, k in zip(labels[first:stop], keys[first:stop]) if k == key]
        seg = _segment(shares[first][0], shares[stop - 1][1], agree)
        out.append(Segment(seg.start, seg.end, seg.text, seg.score, stop - first))
    return out

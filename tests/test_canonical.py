"""Canonical captions (``datasets.canonical``): many wordings of one motion meet in one text,
what the body does is kept (actions, sides, directions, counts), style and mood set apart."""
from __future__ import annotations

import pytest

from motionlang.datasets.canonical import (
    Canonical,
    canonical,
    canonical_text,
    styles_in,
    without_style,
)


@pytest.mark.parametrize("wordings", [
    ("A man is walking forward", "someone walks forward", "The woman strolls forward",
     "a person is strolling forward"),
    ("somebody jogs in a circle", "A person is running in a circle", "he runs in a circle"),
    ("a person waves his left hand twice", "Someone is waving the left hand two times"),
    ("A human squats down", "the person crouches down"),
])
def test_wordings_of_one_motion_meet(wordings):
    assert len({canonical_text(w) for w in wordings}) == 1, [canonical_text(w)
                                                             for w in wordings]


def test_what_the_body_does_is_kept():
    c = canonical("A man is slowly strolling forward, then waves his left hand twice")
    assert c.text == "a person slowly walks forward, then waves left hand 2 times"
    assert canonical_text("waves the right hand") != canonical_text("waves the left hand")
    assert canonical_text("walks backwards") != canonical_text("walks forward")
    assert canonical_text("jumps three times") == "a person jumps 3 times"
    # a noun stays a noun: "at a trot" is a running pace
    assert canonical_text("somebody hurries along at a trot") == (
        "a person hurries along at a run")


def test_style_and_mood_are_set_apart():
    c = canonical("An insecure woman jumps ahead")
    assert c.text == "a person jumps ahead" and c.style == ("an insecure woman",)
    assert canonical("A person walks forward in a rage") == Canonical("a person walks forward",
                                                                      ("in a rage",))
    assert styles_in("walks happily and proudly") == ("happily", "proudly")
    assert without_style("walks forward in a rage") == "walks forward"
    assert canonical("a person walks").style == ()
    # what an encoder reads: the style by its own name, in its own place at the end
    assert canonical_text("A man walks forward in a rage") == (
        "a person walks forward; style: angry")
    assert canonical_text("A man proudly and happily walks") == (
        "a person walks; style: happy, proud")


def test_a_repeated_word_left_after_the_fillers_is_said_once():
    assert canonical_text("a person is walking walking") == "a person walks"
    assert canonical_text("") == "a person"

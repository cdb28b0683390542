"""Canonical captions (``datasets.canonical``): many wordings of one motion meet in one text,
what the body does is kept (actions, sides, directions, counts), style and mood set apart."""
from __future__ import annotations

import pytest

from motionlang.datasets.canonical import (
    Canonical,
    action_verbs,
    canonical,
    canonical_text,
    read_as,
    styles_in,
    without_style,
)


@pytest.mark.parametrize("wordings", [
    ("A man is walking forward", "someone walks forward", "The woman strolls forward",
     "a person is strolling forward"),
    ("somebody jogs in a circle", "A person is running in a circle", "he runs in a circle"),
    ("a person waves his left hand twice", "Someone is waving the left hand two times"),
    ("A human squats down", "the person crouches down"),
    ("someone puts the left hand up", "a person raises the left hand",
     "a man sticking his left hand up in the air"),
    ("somebody takes a left", "a person turns left"),
    ("someone says hello with the right hand", "a person waves with the right hand"),
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
        "a person runs along at a run")


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


def test_action_verbs_change_the_verb_alone():
    """The reading for a model trained on captions as written: other words for an action
    become its verb; subject, style, articles and sides stay as written."""
    assert action_verbs("An old man slowly strolls and puts his left hand up") == \
        "an old man slowly walks and raises his left hand"
    assert action_verbs("someone greets using both palms") == "someone waves using both palms"
    assert action_verbs("a person sits down") == "a person sits down"
    # a noun after an article stays a noun
    assert action_verbs("an old man takes a bow") == "an old man takes a bow"
    assert action_verbs("somebody hurries along at a trot") == "somebody runs along at a run"
    assert action_verbs("takes a right turn") == "turns right"
    assert action_verbs("throws a left jab") == "punches left"
    assert read_as("Someone strolls", "written") == "Someone strolls"
    assert read_as("Someone strolls", "canonical") == canonical_text("Someone strolls")

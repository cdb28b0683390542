"""English for the Bandai Namco labels: every label said, deterministic, mirrored sides;
the ``bandai:`` records (sentences, labels, splits, mirrored takes) and their pairs."""
from __future__ import annotations

import numpy as np
import pytest

from helpers.data import bandai_takes
from motionlang.datasets.bandai_text import (
    CONTENTS,
    STYLES,
    contents_named,
    describe,
    mirror_sentence,
    names_content,
    names_style,
    styles_named,
)
from motionlang.datasets.seq2seq_pairs import build_pairs, load_records
from motionlang.features.joint_map import KIT21_MIRROR, positions21
from motionlang.kinematics.from_positions import mirror_motion

# the labels of the two releases' cfg/content_label.txt and cfg/style_label.txt
DATASET_1 = ("walk run dash walk-back walk-left walk-right bow bye guide byebye respond call "
             "punch kick slash dance-long dance-short".split(),
             "normal happy sad angry proud not-confident masculinity feminine childish old "
             "tired active musical giant chimpira".split())
DATASET_2 = ("walk walk-turn-left walk-turn-right run wave-both-hands wave-left-hand "
             "wave-right-hand raise-up-both-hands raise-up-left-hand raise-up-right-hand".split(),
             "active elderly exhausted feminine masculine normal youthful".split())


@pytest.mark.parametrize("contents,styles", [DATASET_1, DATASET_2])
def test_every_label_pair_gets_sentences_naming_its_style(contents, styles):
    assert len(contents) in (17, 10) and len(styles) in (15, 7)
    assert set(contents) <= set(CONTENTS) and set(styles) <= set(STYLES)
    for c in contents:
        for s in styles:
            got = describe(c, s, n=3)
            assert len({x.text for x in got}) == 3
            for x in got:
                assert (x.content, x.style) == (c, s) and x.text == " ".join(x.text.split())
                assert names_style(x.text, s), x.text
                assert x.states_style or s == "normal"


def test_phrasings_vary_and_synonyms():
    assert len({x.text for x in describe("wave-left-hand", "happy", n=10)}) == 10
    assert styles_named("Someone cheerfully waves their left hand") == {"happy"}
    assert styles_named("an old man walks and turns to the right") == {"old", "elderly"}
    assert names_style("a person walks forward", "normal")
    assert not names_style("a person walks forward", "tired")
    assert not names_style("a happy person walks", "normal")
    assert styles_named("a mad man walks") == {"angry"}
    assert styles_named("the madness walks") == set()   # whole words only


def test_deterministic_given_a_seed():
    a = [describe(c, s, 3, seed=7) for c in CONTENTS for s in STYLES]
    assert a == [describe(c, s, 3, seed=7) for c in CONTENTS for s in STYLES]
    assert a != [describe(c, s, 3, seed=8) for c in CONTENTS for s in STYLES]


def test_mirrored_text_swaps_sides_and_labels():
    for c in ("wave-left-hand", "raise-up-right-hand", "walk-turn-left", "walk-right", "bow"):
        for x in describe(c, "tired", 3):
            m = mirror_sentence(x)
            assert m.style == "tired" and mirror_sentence(m) == x
            if "left" in c or "right" in c:
                side, other = ("left", "right") if "left" in c else ("right", "left")
                assert other in m.text.split() and side not in m.text.split()
                assert m.content == c.replace(side, other)
            else:
                assert (m.text, m.content) == (x.text, c)


def _bandai_folder(tmp_path):
    """A dataset-1 folder of three real takes, and a dataset-2 folder whose five takes are a
    real dataset-1 take renamed (the labels, not the motion, are under test)."""
    src = bandai_takes(["walk-back_normal_001", "bye_happy_001", "bow_old_001"], tmp_path)
    root = tmp_path / "bandai"
    for n, contents, styles in ((1, *DATASET_1), (2, *DATASET_2)):
        top = root / f"Bandai-Namco-Research-Motiondataset-{n}"
        (top / "data").mkdir(parents=True)
        (top / "cfg").mkdir()
        (top / "cfg" / "content_label.txt").write_text("\n".join(f"dataset-{n}_{c}"
                                                                 for c in contents))
        (top / "cfg" / "style_label.txt").write_text("\n".join(f"dataset-{n}_{s}"
                                                               for s in styles))
    for take in ("walk-back_normal_001", "bye_happy_001", "bow_old_001"):
        (root / "Bandai-Namco-Research-Motiondataset-1" / "data" / f"dataset-1_{take}.bvh"
         ).write_bytes((src / f"{take}.bvh").read_bytes())
    for t in range(1, 6):
        (root / "Bandai-Namco-Research-Motiondataset-2" / "data" /
         f"dataset-2_wave-left-hand_elderly_{t:03d}.bvh").write_bytes(
            (src / "walk-back_normal_001.bvh").read_bytes())
    return root


def test_bandai_records_and_pairs(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    root = _bandai_folder(tmp_path)
    recs = load_records(f"bandai:{root}")
    assert len(recs) == 8 and recs == sorted(recs, key=lambda r: r.id)
    by_id = {r.id: r for r in recs}
    bye = by_id["dataset-1_bye_happy_001"]
    assert bye.labels == {"content": "bye", "style": "happy"} and bye.split == "train"
    assert len(bye.annotations) == 3 and all(names_style(t, "happy") for t in bye.annotations)
    assert [by_id[f"dataset-2_wave-left-hand_elderly_{t:03d}"].split for t in range(1, 6)] == [
        "train", "train", "train", "val", "test"]
    assert [r.annotations for r in load_records(f"bandai:{root}")] == [r.annotations
                                                                       for r in recs]
    # long takes are left out as for the other datasets (walk-back is 1 s, the others > 3 s)
    assert {r.id for r in load_records(f"bandai:{root}", max_seconds=2.0)} == set(by_id) - {
        "dataset-1_bow_old_001", "dataset-1_bye_happy_001"}
    pairs = build_pairs(f"bandai:{root}", features="positions", offsets=1)
    assert pairs.splits["val"] == ["dataset-2_wave-left-hand_elderly_004"]
    assert pairs.splits["test"] == ["dataset-2_wave-left-hand_elderly_005"]
    assert len(pairs.items["train"]) == 6 * 3 and pairs.references["val"][
        "dataset-2_wave-left-hand_elderly_004"] == by_id[
        "dataset-2_wave-left-hand_elderly_004"].annotations


def test_mirrored_takes(tmp_path, monkeypatch):
    from motionlang.datasets.bandai import load_bandai_text
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    root = _bandai_folder(tmp_path)
    recs = {r.id: r for r in load_bandai_text(root, mirror=True)}
    assert len(recs) == 16
    a = recs["dataset-2_wave-left-hand_elderly_005"]
    m = recs["Mdataset-2_wave-left-hand_elderly_005"]
    assert (m.content, m.style, m.split, m.mirrored) == ("wave-right-hand", "elderly", "test",
                                                         True)
    assert all("right" in t.split() and "left" not in t.split() for t in m.annotations)
    # the Bandai rig's rest pose is not mirror-symmetric: mirrored by positions, exactly
    p, q = positions21(a.load_motion()), positions21(m.load_motion())
    assert np.abs(p[:, list(KIT21_MIRROR)] * [-1, 1, 1] - q).max() < 1e-6
    assert m.load_motion().meta["content"] == "wave-right-hand"


def test_mirror_motion_keeps_motion_mirror_on_symmetric_rigs(tiny_motion):
    got = mirror_motion(tiny_motion)
    want = tiny_motion.mirror()
    assert got.skeleton is tiny_motion.skeleton
    assert np.array_equal(got.joint_angles, want.joint_angles)


def test_mirror_motion_by_positions_on_an_along_x_rig(tmp_path):
    """Bandai's rest pose lays every bone along its local x axis: ``Motion.mirror`` would
    fold the body, so the mirror goes by positions, exactly."""
    from helpers.rigs import RIGS, write
    from motionlang.formats import read_motion
    m = read_motion(write(RIGS["bandai"], tmp_path))
    got = mirror_motion(m)
    assert got.source_format == "positions" and got.meta["mirrored"] is True
    p, q = positions21(m), positions21(got)
    assert np.abs(p[:, list(KIT21_MIRROR)] * [-1, 1, 1] - q).max() < 1e-6
    assert np.abs(positions21(mirror_motion(got)) - p).max() < 1e-6


def test_every_grammar_sentence_names_its_content_and_no_other():
    for c in CONTENTS:
        for s in STYLES:
            for x in describe(c, s, n=6) + [mirror_sentence(x) for x in describe(c, s, n=3)]:
                got = contents_named(x.text)
                assert names_content(x.text, x.content), x.text
                assert got == {x.content} or got == {"dance-short", "dance-long"}, (x.text, got)


@pytest.mark.parametrize("text,content", [
    ("a person walks 4 steps forward slowly", "walk"),
    ("someone jogs", "run"), ("a man is running in place", "run"),
    ("a person sprints", "dash"), ("the person steps back", "walk-back"),
    ("a person waves", None), ("a person waves the right arm", "wave-right-hand"),
    ("someone waves goodbye with both hands", "byebye"), ("he waves bye", "bye"),
    ("a person lifts both arms", "raise-up-both-hands"),
    ("a person raises a hand to respond", "respond"),
    ("a person walks to the right and turns", "walk-turn-right"),
    ("a person walks to the right", "walk-right"), ("a person bows", "bow"),
    ("a person kicks twice", "kick"), ("someone dances for a while", "dance-long"),
    ("a person jumps", None)])
def test_content_synonyms(text, content):
    assert contents_named(text) == ({content} if content else set())


def test_sides_must_match():
    assert names_content("waves the left hand", "wave-left-hand")
    assert not names_content("waves the left hand", "wave-right-hand")
    assert not names_content("waves the left hand", "wave-both-hands")
    assert not names_content("walks and turns to the left", "walk-turn-right")
    assert not names_content("walks and turns to the left", "walk")
    assert not names_content("raises the left and the right hand", "raise-up-left-hand")
    assert not names_content("walks forward", "walk-left")

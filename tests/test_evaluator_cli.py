"""``motionlang train evaluator`` and ``evaluate-t2m --protocol guo`` on a tiny procedural
corpus with a tiny evaluator: the run folder, the table's rows and files, the public
weights' path giving the same table as the same weights in a motionlang checkpoint, and
bad inputs as one line with exit code 2."""
from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from helpers.evaluator import TINY, tiny_corpus, tiny_evaluator
from motionlang.cli.main import main
from motionlang.errors import MotionlangError

# 38 of the 48 motions train, 5 test: R-precision in batches of 4, a few shuffles
GUO = ["--protocol", "guo", "--rp-batch", "4", "--repeats", "2"]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return tiny_corpus(tmp_path_factory.mktemp("corpus"))


@pytest.fixture(scope="module")
def run(corpus, tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("MOTIONLANG_CACHE", str(tmp_path_factory.mktemp("cache")))
    yield tiny_evaluator(corpus, tmp_path_factory.mktemp("runs") / "evaluator")
    mp.undo()


def test_train_evaluator_writes_a_run_folder(run):
    from motionlang.models.registry import load_model
    assert {"model.pt", "best.pt", "last.pt", "history.json", "commands.jsonl"} <= {
        p.name for p in run.iterdir()}
    assert (run / "splits" / "test.txt").read_text().split()
    model = load_model(run, kind="evaluator")
    assert model.config.motion_dim == 251 and model.config.embed_dim == 8
    assert json.loads((run / "commands.jsonl").read_text().splitlines()[0])["grad_clip"] == 0.5
    assert len(model.config.bones) == 20     # every motion laid on one body by default


def test_a_resumed_evaluator_keeps_the_body_it_started_on(corpus, tmp_path, monkeypatch):
    from motionlang.models.registry import load_model
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "ev"
    args = ["train", "evaluator", "--data", str(corpus), "--out", str(out),
            "--batch-size", "16", *TINY]
    assert main([*args, "--epochs", "1", "--as-given"]) == 0
    assert load_model(out, kind="evaluator").config.bones is None
    assert main([*args, "--epochs", "2", "--resume"]) == 0     # no --as-given: kept anyway
    assert load_model(out / "last.pt", kind="evaluator").config.bones is None


def test_ml_train_runs_the_evaluator_recipe(corpus, tmp_path, monkeypatch):
    import motionlang as ml
    from motionlang.models.registry import load_model
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    sizes = {k: 8 for k in ("embed_dim", "text_hidden", "motion_hidden", "movement_hidden",
                            "movement_latent")}
    path = ml.train("evaluator", str(corpus), tmp_path / "ev", epochs=1, batch_size=16,
                    as_given=True, loss="infonce", **sizes)
    assert path == tmp_path / "ev" / "model.pt"
    model = load_model(path, kind="evaluator")
    assert model.config.loss == "infonce" and model.config.embed_dim == 8
    assert model.config.bones is None                      # as_given: each on its own bones
    assert not (tmp_path / "ev" / "LICENSE.txt").exists()  # no restricting source
    for bad, message in (({"motion_dim": 10}, "come from the data"),
                         ({"body": "mixamo"}, "EvaluatorDataOptions.body"),
                         ({"embed_dim": 5000}, "embed_dim must be an integer in 1..4096")):
        with pytest.raises(MotionlangError, match=message):
            ml.train("evaluator", str(corpus), tmp_path / "bad", **bad)
    assert not (tmp_path / "bad").exists()   # refused before anything is written


def test_train_evaluator_options_from_the_configs():
    from motionlang.cli.main import build_parser
    args = build_parser().parse_args(["train", "evaluator", "--data", "corpus", "--data-body",
                                      "smpl", "--loss", "infonce", "--as-given"])
    assert (args.body, args.loss, args.as_given, args.epochs, args.grad_clip) == (
        "smpl", "infonce", True, 30, 0.5)


def test_guo_table_rows_and_files(run, corpus, tmp_path, capsys):
    out = tmp_path / "guo"
    assert main(["evaluate-t2m", *GUO, "--evaluator", str(run), "--data", str(corpus),
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    for row in ("ground truth", "nearest neighbour", "standing still", "l2m"):
        assert f"| {row} |" in text
    assert "(kit body, every motion laid on one body)" in text
    assert (out / "t2m_guo.md").read_text() == text
    report = json.loads((out / "t2m_guo.json").read_text())
    assert report["protocol"] == "guo" and report["pairs"] == 5 and report["body"] == "kit"
    truth = report["rows"]["ground truth"]
    assert set(truth) >= {"R-precision top-1", "R-precision top-3", "FID", "MM-Dist",
                          "Diversity", "TMR R@1 %", "TMR MedR"}
    mean, half = truth["R-precision top-3"]
    assert 0 <= mean <= 1 and half >= 0
    assert truth["FID"][0] > 1e-6   # test against training motions, not a set against itself
    # the motion-to-text half: the packaged M2L by default, beside ground truth and NN
    assert set(report["m2t_rows"]) == {"ground truth", "nearest neighbour", "m2l"}
    m2l = report["m2t_rows"]["m2l"]
    assert 0 <= m2l["BLEU@4"] <= 1 and 0 <= m2l["R-precision top-3"][0] <= 1
    assert "Motion to text" in text and (out / "t2m_guo.png").stat().st_size > 1000
    m2t_line = [l for l in text.splitlines() if l.startswith("| m2l |")][-1]
    assert m2t_line.split(" | ")[2] == f"{m2l['BLEU@4']:.3f}"   # text scores: 3 decimals
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]   # no temp files


def test_guo_regenerates_sampling_models_for_each_repeat(run, corpus, capsys):
    """--regenerate: one generation per repeat (seeds 0, 1, ...), so FID has a spread."""
    common = ["evaluate-t2m", *GUO, "--evaluator", str(run), "--data", str(corpus),
              "--m2l", "none", "--model", "sampled=l2m:method=sample", "--repeats", "3"]
    assert main([*common, "--regenerate"]) == 0
    out = capsys.readouterr()
    row = next(l for l in out.out.splitlines() if l.startswith("| sampled |"))
    fid_mean, fid_half = row.split("|")[5].split(" ± ")
    assert float(fid_half) > 0   # three generations differ
    assert main(common) == 0
    row = next(l for l in capsys.readouterr().out.splitlines() if l.startswith("| sampled |"))
    assert float(row.split("|")[5].split(" ± ")[1]) == 0   # one generation, reshuffled
    assert main(["evaluate-t2m", *GUO, "--evaluator", str(run), "--data", str(corpus),
                 "--regenerate"]) == 2      # the packaged l2m, decoding its means
    assert "--regenerate needs a model that samples, e.g. --model l2m:method=sample" in \
        capsys.readouterr().err


def test_guo_ground_truth_fid_against_the_validation_motions(run, corpus, tmp_path, capsys):
    common = ["evaluate-t2m", *GUO, "--evaluator", str(run), "--data", str(corpus),
              "--m2l", "none"]
    fids = {}
    for ref in ("train", "val"):
        assert main([*common, "--fid-reference", ref, "-o", str(tmp_path / ref)]) == 0
        assert f"test against {'training' if ref == 'train' else 'val'} motions" in \
            capsys.readouterr().out
        rows = json.loads((tmp_path / ref / "t2m_guo.json").read_text())["rows"]
        fids[ref] = rows["ground truth"]["FID"][0]
    assert fids["val"] > 0 and fids["val"] != fids["train"]


def test_guo_without_motion_to_text(run, corpus, capsys):
    assert main(["evaluate-t2m", *GUO, "--evaluator", str(run), "--data", str(corpus),
                 "--m2l", "none"]) == 0
    assert "Motion to text" not in capsys.readouterr().out


def test_official_weights_give_the_table_of_the_same_weights(run, corpus, tmp_path, capsys):
    """The public checkpoint layout (three state dicts in one file, mean.npy / std.npy,
    GloVe-format word vectors) loads into the same modules: the same table as those weights
    saved as a motionlang evaluator."""
    from motionlang.models.evaluator.config import EvaluatorConfig
    from motionlang.models.evaluator.model import TextMotionEvaluator
    from motionlang.models.evaluator.text import TextFileVectors
    words = tmp_path / "words.txt"
    rng = np.random.default_rng(0)
    words.write_text("".join(f"{w} " + " ".join(f"{x:.4f}" for x in rng.normal(size=6)) + "\n"
                             for w in ("unk", "a", "person", "walk", "forward", "wave", "run")))
    vectors = TextFileVectors(words)
    torch.manual_seed(0)
    model = TextMotionEvaluator(EvaluatorConfig(word_dim=6, **{
        k: 8 for k in ("text_hidden", "motion_hidden", "movement_hidden", "movement_latent",
                       "embed_dim")}), np.full(251, 0.5), np.full(251, 2.0), vectors)
    torch.save({k: getattr(model, k).state_dict() for k in
                ("movement_encoder", "motion_encoder", "text_encoder")}, tmp_path / "finest.tar")
    np.save(tmp_path / "mean.npy", model.mean)
    np.save(tmp_path / "std.npy", model.std)
    model.save(tmp_path / "ours.pt")
    common = [*GUO, "--data", str(corpus), "--word-vectors", str(words), "--model", "l2m"]
    assert main(["evaluate-t2m", *common, "--evaluator", str(tmp_path / "ours.pt")]) == 0
    ours = capsys.readouterr().out
    assert main(["evaluate-t2m", *common, "--evaluator-official", str(tmp_path / "finest.tar"),
                 "--mean", str(tmp_path / "mean.npy"), "--std", str(tmp_path / "std.npy")]) == 0
    official = capsys.readouterr().out
    assert official.split("\n", 1)[1] == ours.split("\n", 1)[1]   # the title names the file


@pytest.mark.parametrize("extra, message", [
    ([], "needs --evaluator E or --evaluator-official"),
    (["--evaluator", "E", "--evaluator-official", "T"], "one of them"),
    (["--evaluator", "E", "--mean", "m.npy"], "--mean and --std go with"),
    (["--evaluator-official", "T", "--mean", "m.npy"], "--mean and --std go with"),
    (["--evaluator", "E", "--multimodality", "5"], "more than 10"),
    (["--evaluator", "E", "--autoencode"], "--autoencode applies to --protocol ape"),
    (["--evaluator", "E", "--true-start"], "--true-start applies to --protocol ape"),
    (["--evaluator", "/nonexistent/e.pt"], "no such model"),
])
def test_bad_guo_inputs_are_one_line(extra, message, corpus, capsys):
    assert main(["evaluate-t2m", "--protocol", "guo", "--data", str(corpus), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_bad_inputs_against_a_trained_evaluator(run, corpus, tmp_path, capsys):
    cases = [
        (["evaluate-t2m", "--data", str(corpus), "--evaluator", str(run), "--model", "l2m"],
         "--evaluator applies to --protocol guo"),
        (["evaluate-t2m", "--data", str(corpus)], "needs at least one --model"),
        (["evaluate-t2m", "--protocol", "guo", "--data", str(corpus), "--evaluator", str(run)],
         "R-precision needs at least --rp-batch 32"),
        (["evaluate-t2m", *GUO, "--data", str(corpus), "--evaluator", str(run), "--model",
          str(run)], "not l2m or twostream"),
        (["evaluate-t2m", *GUO, "--data", str(corpus), "--model", "l2m", "--evaluator", "l2m"],
         "kind l2m, not evaluator"),
        (["evaluate-t2m", *GUO, "--data", str(corpus), "--evaluator", str(run), "--m2l", "l2m"],
         "kind l2m, not m2l"),
        (["evaluate-t2m", "--data", str(corpus), "--model", "l2m", "--m2l", "m2l"],
         "--m2l applies to --protocol guo"),
        (["train", "evaluator", "--data", str(corpus), "--body", "mixamo"], "--body"),
        (["train", "evaluator", "--data", str(corpus), "--out", str(tmp_path / "r"),
          "--embed-dim", "5000"], "--embed-dim must be an integer in 1..4096"),
        (["evaluate-t2m", *GUO, "--data", str(corpus), "--evaluator", str(run),
          "--rp-batch", "1"], "--rp-batch must be an integer >= 2"),
        (["train", "evaluator", "--data", str(tmp_path / "none"), "--out", str(tmp_path / "r")],
         str(tmp_path / "none")),
        (["train", "evaluator", "--data", str(corpus), "--resume", "--out",
          str(tmp_path / "fresh")], "last.pt"),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, (argv, err)


def test_word_vectors_must_fit_the_evaluator(run, corpus, tmp_path, capsys):
    words = tmp_path / "w.txt"
    words.write_text("unk 1 2 3\nwalk 1 2 3\n")
    assert main(["evaluate-t2m", *GUO, "--data", str(corpus), "--evaluator", str(run),
                 "--word-vectors", str(words)]) == 2
    assert "3-d words, the evaluator reads 50-d ones" in capsys.readouterr().err
    words.write_text("walk 1 2 3\nrun 1 x\n")
    assert main(["evaluate-t2m", *GUO, "--data", str(corpus), "--evaluator", str(run),
                 "--word-vectors", str(words)]) == 2
    assert "w.txt:2: not a word and 3 numbers" in capsys.readouterr().err

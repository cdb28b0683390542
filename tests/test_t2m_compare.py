"""The text-to-motion comparison table: items from a corpus, metrics of oracle and wrong
"models", the order check on compositional items, L2M through forward kinematics, the
trajectory figures and the ``evaluate-t2m`` command."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from helpers.patching import patch_everywhere
from helpers.twostream import HashTokens
from motionlang.errors import MotionlangError
from motionlang.evaluation.action_order import segment_labels
from motionlang.evaluation.t2m.compare import (
    GROUND_TRUTH,
    NEAREST,
    compare,
    eval_items,
    evaluate_model,
    fit_prototypes,
    markdown_table,
    positions_to_features,
)

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    from motionlang.datasets.synth import write_corpus
    root = tmp_path_factory.mktemp("corpus")
    write_corpus(root, n=12, seed=5, workers=1, show_progress=False)
    return root


@pytest.fixture(scope="module")
def data(corpus, tmp_path_factory):
    from motionlang.datasets.position_items import build_twostream_data
    return build_twostream_data(corpus, cache_dir=tmp_path_factory.mktemp("cache"))


def test_items_and_feature_round_trip(data):
    items = eval_items(data, "train")
    assert len(items) == len(data.splits["train"])
    for it in items:
        seq = data.sequences[it.id]
        assert it.sentence in data.records[it.id].annotations
        assert it.target.shape == (len(seq), 21, 3)
        # anchored: frame 0's root above the origin
        np.testing.assert_allclose(it.target[0, 0, [0, 2]], 0.0, atol=1e-9)
        # the generated-motion path (positions -> features) reproduces encode exactly
        np.testing.assert_allclose(positions_to_features(data.features, it.target), seq,
                                   atol=1e-4)
        assert len(it.ranges) == len(it.truth) and all(0 <= a < b <= len(seq)
                                                       for a, b in it.ranges)
    assert any(it.compositional for it in items)


def test_oracle_and_wrong_models(data):
    items = eval_items(data, "train")
    protos = fit_prototypes(data)
    by_sentence = {it.sentence: it.target for it in items}
    oracle = evaluate_model(lambda s, t: by_sentence[s], items, data.features, protos)
    assert oracle["ape_local"] < 1e-6 and oracle["ape_root"] < 1e-6
    assert oracle["ave_local"] < 1e-6
    comp = [it for it in items if it.compositional]
    assert oracle["n_compositional"] == len(comp) > 0
    # order accuracy = that of the true motions' own features under the same prototypes
    direct = np.mean([segment_labels(data.sequences[it.id], it.ranges, protos) == it.truth
                      for it in comp])
    assert oracle["order_accuracy"] == pytest.approx(direct)
    labels = [segment_labels(data.sequences[it.id], it.ranges, protos) for it in comp]
    assert oracle["first_segment_accuracy"] == pytest.approx(
        np.mean([l[0] == it.truth[0] for l, it in zip(labels, comp)]))
    # a model that stands still in the first pose: errors in mm, and APE of the root = the
    # mean distance of the true root from its start
    still = evaluate_model(lambda s, t: np.repeat(by_sentence[s][:1], t, axis=0), items,
                           data.features, protos)
    assert still["ape_local"] > 10.0
    roots = np.concatenate([np.linalg.norm(it.target[:, 0] - it.target[:1, 0], axis=-1)
                            for it in items])
    assert still["ape_root"] == pytest.approx(1000 * roots.mean(), rel=1e-6)
    # time-reversed motions perform the actions in the wrong order
    rev = evaluate_model(lambda s, t: by_sentence[s][::-1], items, data.features, protos)
    assert rev["order_accuracy"] < oracle["order_accuracy"] or oracle["order_accuracy"] == 0
    table = markdown_table({"oracle": oracle, "still": still})
    assert table.count("\n| ") == 2 and "| oracle | 0.0 |" in table
    first, later = oracle["first_segment_accuracy"], oracle["later_segment_accuracy"]
    assert f"| {first:.2f} / {later:.2f} |" in table


def _tiny_l2m(data):
    from motionlang.datasets.text import Vocabulary
    from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
    vocab = Vocabulary.build([s for r in data.records.values() for s in r.annotations])
    torch.manual_seed(0)
    cfg = L2MConfig(vocab_size=len(vocab), n_features=66, embed_dim=8, enc_hidden=8,
                    enc_layers=1, dec_hidden=8, dec_layers=1, n_components=2, dropout=0.0,
                    max_frames=20)
    return LanguageToMotion(cfg, vocab, features=data.features).eval()


def test_l2m_on_the_test_subjects_bodies(data):
    """An angles L2M with --true-start: the same generated angles drive each test subject's
    own MMM body, so only bone lengths change (and the root's start stays at the origin)."""
    from motionlang.datasets.text import Vocabulary
    from motionlang.features.angles import AnglesFeatures
    from motionlang.features.frames import model_dim
    from motionlang.formats.mmm_model import mmm_skeleton
    from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
    from motionlang.models.t2m import generate_positions21
    fs = AnglesFeatures().fit([r.load_motion() for r in list(data.records.values())[:3]])
    vocab = Vocabulary.build([s for r in data.records.values() for s in r.annotations])
    torch.manual_seed(0)
    # frames as trained models see them: without the features' active flag
    l2m = LanguageToMotion(L2MConfig(vocab_size=len(vocab), n_features=model_dim(fs), embed_dim=8,
                                     enc_hidden=8, enc_layers=1, dec_hidden=8, dec_layers=1,
                                     n_components=2, dropout=0.0, max_frames=12),
                           vocab, features=fs).eval()
    results, _ = compare({"L2M": l2m}, data, split="train", limit=3, figures=0,
                         true_start=True)
    body, other = results["L2M, on the test subject's body"]["generated"], 0
    for it in eval_items(data, "train", 3):
        h = data.records[it.id].meta["subject"]["height_m"]
        np.testing.assert_allclose(body[it.id], generate_positions21(
            l2m, it.sentence, len(it.target), skeleton=mmm_skeleton(h)))
        # taller or shorter than the mean build: the same pose at another size
        mean = results["L2M"]["generated"][it.id]
        if abs(h - fs.subject_height) > 0.02:
            assert not np.allclose(body[it.id], mean)
            other += 1
    assert other >= 1
    # the second row: on the same body, each motion starts with the test motion's first
    # frame in the L2M's features (its posture) and goes on from there
    from motionlang.features.frames import motion_frames
    primed = results["L2M, from the test motion's first pose, on its body"]["generated"]
    for it in eval_items(data, "train", 3):
        rec = data.records[it.id]
        h = rec.meta["subject"]["height_m"]
        f0 = motion_frames(fs, rec.load_motion())[0][0]
        np.testing.assert_allclose(primed[it.id], generate_positions21(
            l2m, it.sentence, len(it.target), skeleton=mmm_skeleton(h), first_frame=f0))
        assert not np.allclose(primed[it.id], body[it.id])
        # its first frame is the test motion's first pose (joints relative to the root;
        # the angles features round-trip the pose to ~1 mm)
        want = it.target[0] - it.target[0, :1]
        np.testing.assert_allclose(primed[it.id][0] - primed[it.id][0, :1], want, atol=5e-3)


def test_l2m_and_twostream_positions(data):
    from motionlang.models.t2m import generate_positions21
    from motionlang.models.twostream.config import TwoStreamConfig
    from motionlang.models.twostream.model import TwoStreamModel
    l2m = _tiny_l2m(data)
    p = generate_positions21(l2m, "a person walks forward", 9)
    assert p.shape == (9, 21, 3) and np.isfinite(p).all()
    np.testing.assert_allclose(p[0, 0, [0, 2]], 0.0, atol=1e-9)
    s1 = generate_positions21(l2m, "a person walks forward", 9, method="sample", seed=1)
    assert s1.shape == (9, 21, 3) and np.isfinite(s1).all()
    np.testing.assert_array_equal(
        s1, generate_positions21(l2m, "a person walks forward", 9, method="sample", seed=1))
    assert not np.allclose(s1, p)            # a draw, not the heaviest component's means
    torch.manual_seed(0)
    ts = TwoStreamModel(TwoStreamConfig(h1=4, h2=8, h=16, disc_hidden=8),
                        data.features.normalizer, text_encoder=HashTokens()).eval()
    q = generate_positions21(ts, "a person walks forward", 9)
    assert q.shape == (9, 21, 3)
    np.testing.assert_allclose(q, ts.generate_positions("a person walks forward", 9))


def test_compare_writes_table_report_and_figures(data, tmp_path):
    from motionlang.datasets.text import tokenize
    from motionlang.models.twostream.config import TwoStreamConfig
    from motionlang.models.twostream.model import TwoStreamModel
    torch.manual_seed(0)
    ts = TwoStreamModel(TwoStreamConfig(h1=4, h2=8, h=16, disc_hidden=8),
                        data.features.normalizer, text_encoder=HashTokens()).eval()
    from motionlang.models.length import SentenceLength
    ts.length_model = SentenceLength.fit(["a person"], [7])
    l2m = _tiny_l2m(data)
    l2m.length_model = SentenceLength.fit(["a person"], [3])   # frames at its own rate
    results, table = compare({"two-stream": ts, "L2M": l2m}, data, split="train",
                             limit=4, out_dir=tmp_path, figures=2, autoencode=True,
                             true_start=True)
    ae = "two-stream, from the motion's own embedding"   # two-stream models only
    ts_start = "two-stream, from the test motion's first pose"
    still_start = "no motion (the test motion's first pose)"
    # a positions L2M has no body of its own to scale: no row on the subjects' bodies
    assert set(results) == {"two-stream", "L2M", "no motion (mean first pose)", GROUND_TRUTH,
                            NEAREST, ae, ts_start, still_start}
    for it in eval_items(data, "train", 4):
        np.testing.assert_array_equal(results[still_start]["generated"][it.id],
                                      np.repeat(it.target[:1], len(it.target), axis=0))
    for rid, p in results[ts_start]["generated"].items():   # the sentence, the true start
        it = next(i for i in eval_items(data, "train", 4) if i.id == rid)
        want = ts.positions(ts.generate(it.sentence, len(it.target),
                                        start=torch.as_tensor(data.sequences[rid][0])))
        # the start pose went through decode and encode (1e-4 apart), and a global path
        # sums the frames' steps
        np.testing.assert_allclose(p, want, atol=1e-3)
    assert results[ts_start]["ape_local"] != results["two-stream"]["ape_local"]
    # evaluated on the training split, every sentence retrieves the first training motion
    # with the same words in the same order: its own, unless an earlier one has them too
    nearest, own = results[NEAREST], 0
    for it in eval_items(data, "train", 4):
        g = nearest["generated"][it.id]
        assert g.shape == it.target.shape
        same = [r for r in data.splits["train"] if any(
            tokenize(a) == tokenize(it.sentence) for a in data.records[r].annotations)]
        if same[0] == it.id:
            np.testing.assert_allclose(g, it.target, atol=1e-9)
            own += 1
    assert own >= 1 and nearest["ape_local"] < results["no motion (mean first pose)"]["ape_local"]
    # the autoencoder row decodes each test motion from its own embedding and first frame
    for rid, p in results[ae]["generated"].items():
        seq = data.sequences[rid]
        want = ts.positions(ts.decoder(ts.encode_motion(torch.as_tensor(seq[None]).float(),
                                                        torch.tensor([len(seq)])),
                                       torch.as_tensor(seq[:1]).float(), len(seq))[0])
        np.testing.assert_allclose(p, want, atol=1e-4)
    with pytest.raises(MotionlangError, match=r"motion must be \(T >= 1, 66\)"):
        ts.reconstruct(torch.zeros(5, 3))
    truth = results[GROUND_TRUTH]
    assert truth["ape_local"] == 0.0 and truth["ape_root"] == 0.0
    items = eval_items(data, "train", 4)
    comp = [it for it in items if it.compositional]
    direct = np.mean([segment_labels(data.sequences[it.id], it.ranges, fit_prototypes(data))
                      == it.truth for it in comp]) if comp else math.nan
    assert truth["order_accuracy"] == pytest.approx(direct, nan_ok=True)
    still = results["no motion (mean first pose)"]
    assert still["ave_local"] > 0 and still["ave_root"] > 0  # the targets move, it does not
    g = next(iter(still["generated"].values()))
    np.testing.assert_array_equal(g[0], g[-1])
    assert (tmp_path / "t2m_table.md").read_text() == table
    report = json.loads((tmp_path / "t2m_report.json").read_text())
    lm = SentenceLength.from_items(data.items["train"])
    items4 = eval_items(data, "train", 4)
    refit = report["length_model"]["refit on the whole training motions"]
    assert refit["mae_frames"] == pytest.approx(np.mean(
        [abs(lm.frames(it.sentence) - len(it.target)) for it in items4]))
    assert refit["n"] == 4 and "Sentence -> length" in table
    # the two-stream model's own length model: fitted on one sentence, it always says 7
    assert report["length_model"]["two-stream"]["mae_frames"] == pytest.approx(
        np.mean([abs(7 - len(it.target)) for it in items4]))
    # and the L2M's: on positions features it counts frames at 12.5 Hz too (an angles
    # L2M's, at 10 Hz, would be left out)
    assert set(report["length_model"]) == {"refit on the whole training motions", "two-stream",
                                           "L2M"}
    for name, r in report["results"].items():
        assert r["n_items"] == 4
        assert math.isclose(r["ape_local"], results[name]["ape_local"])
    pngs = sorted(tmp_path.glob("trajectory_*.png"))
    assert 1 <= len(pngs) <= 2 and all(p.stat().st_size > 1000 for p in pngs)


def test_evaluate_command(corpus, data, tmp_path, monkeypatch, capsys):
    import motionlang.models.registry as registry
    from motionlang.cli.main import main
    from motionlang.models.twostream.config import TwoStreamConfig
    from motionlang.models.twostream.model import TwoStreamModel
    torch.manual_seed(0)
    TwoStreamModel(TwoStreamConfig(h1=4, h2=8, h=16, disc_hidden=8, text_dim=8),
                   data.features.normalizer).save(tmp_path / "ts.pt")
    _tiny_l2m(data).save(tmp_path / "l2m.pt")
    real = registry.load_model
    patch_everywhere(monkeypatch, registry, "load_model", lambda p, kind=None: real(
        p, kind, **({"text_encoder": HashTokens()} if registry.checkpoint_kind(p) == "twostream"
                    else {})))
    rc = main(["evaluate-t2m", "--data", str(corpus), "--model", f"ts={tmp_path / 'ts.pt'}",
               "--model", str(tmp_path / "l2m.pt"), "--split", "train", "--limit", "3",
               "--figures", "0", "-o", str(tmp_path / "eval")])
    out = capsys.readouterr().out
    assert rc == 0 and "| ts |" in out and "| l2m |" in out
    assert (tmp_path / "eval" / "t2m_table.md").exists()
    assert not list((tmp_path / "eval").glob("*.png"))
    first = json.loads((tmp_path / "eval" / "t2m_report.json").read_text())
    mean_l2m = first["results"]["l2m"]
    assert first["options"] == {"ts": {}, "l2m": {"method": "mean"}}
    # each row decodes with its own model's options: the same L2M twice, two rows
    l2m = str(tmp_path / "l2m.pt")
    assert main(["evaluate-t2m", "--data", str(corpus), "--model", l2m,
                 "--model", f"{l2m}:method=sample", "--split", "train", "--limit", "3",
                 "--figures", "0", "-o", str(tmp_path / "eval")]) == 0
    report = json.loads((tmp_path / "eval" / "t2m_report.json").read_text())
    sampled = report["results"]["l2m:method=sample"]
    assert report["results"]["l2m"]["ape_local"] == mean_l2m["ape_local"]
    assert sampled["ape_local"] != mean_l2m["ape_local"]     # other motions were scored
    assert report["options"]["l2m:method=sample"] == {"method": "sample"}
    capsys.readouterr()
    for spec, msg in ((f"{l2m}:width=3", "width applies to 'sample' and 'beam'"),
                      (f"{l2m}:method=sample,rerank=m2l.pt", "rerank ranks several motions"),
                      (f"{l2m}:tempo=2", "unknown option tempo"),
                      (f"{tmp_path / 'ts.pt'}:method=sample", "unknown option method"),
                      (f"{l2m}:method=sample,width=two", "'two' is not a valid int")):
        assert main(["evaluate-t2m", "--data", str(corpus), "--model", spec,
                     "-o", str(tmp_path / "rr")]) == 2
        err = capsys.readouterr().err
        assert msg in err and f"--model {spec}" in err and err.count("\n") == 1, err
    assert main(["evaluate-t2m", "--data", str(corpus), "--model", l2m, "--model",
                 f"{tmp_path}/./l2m.pt", "-o", str(tmp_path / "rr")]) == 2
    assert "a second row named 'l2m'; give one a label" in capsys.readouterr().err
    assert not (tmp_path / "rr").exists()
    assert main(["evaluate-t2m", "--data", str(corpus), "--model", str(tmp_path / "l2m.pt"),
                 "--autoencode", "-o", str(tmp_path / "ae")]) == 2
    assert "--autoencode needs a two-stream model" in capsys.readouterr().err
    assert not (tmp_path / "ae").exists()
    assert main(["evaluate-t2m", "--data", str(corpus), "--model", str(tmp_path / "l2m.pt"),
                 "--split", "train", "--limit", "3", "--oracle", "1000",
                 "-o", str(tmp_path / "or")]) == 2
    assert "no test motion has 1000 training motions" in capsys.readouterr().err
    assert not (tmp_path / "or").exists()


def test_positions_of_the_sample_an_m2l_ranks_first(data, monkeypatch):
    """width W with a reranker: the motion is the best of the same W samples by the M2L's
    log P(sentence | motion), decoded as without one. A ranker that prefers the L2M's least
    likely sample shows that its choice, not the L2M's, is decoded."""
    import motionlang.models.seq2seq.decode.rerank as rr
    from motionlang.models.seq2seq.decode.search import generate_features
    from motionlang.models.seq2seq.m2l import M2LConfig, MotionToLanguage
    from motionlang.models.t2m import anchor, fit_length, generate_positions21
    l2m = _tiny_l2m(data)
    torch.manual_seed(1)
    m2l = MotionToLanguage(M2LConfig(n_features=66, vocab_size=len(l2m.vocab), enc_hidden=8,
                                     dec_hidden=8, embed_dim=8, dropout=0.0), l2m.vocab,
                           features=data.features).eval()
    sentence = "a person walks forward"
    samples = generate_features(l2m, sentence, width=4, method="sample", max_frames=8, seed=2)
    # the real ranker scores every sample; then one that likes the last best
    assert len(set(np.round(rr.sentence_log_probs(m2l, [f for f, _ in samples], sentence),
                            5))) == 4
    monkeypatch.setattr(rr, "sentence_log_probs",
                        lambda model, motions, s: np.arange(len(motions), dtype=float))
    want = fit_length(anchor(data.features.decode(samples[-1][0])), 8)
    got = generate_positions21(l2m, sentence, 8, seed=2, method="sample", width=4,
                               reranker=m2l)
    np.testing.assert_allclose(got, want, atol=1e-5)
    likeliest = generate_positions21(l2m, sentence, 8, seed=2, method="sample", width=4)
    np.testing.assert_allclose(likeliest, fit_length(anchor(data.features.decode(
        samples[0][0])), 8), atol=1e-5)
    assert not np.allclose(likeliest, got)


def test_generate_any_passes_l2m_options(data):
    from motionlang.models.t2m import generate_any
    hyps = generate_any(_tiny_l2m(data), "a person walks forward", width=2, method="beam",
                        max_frames=6, seed=1)
    assert len(hyps) == 2 and hyps[0][1] >= hyps[1][1]
    for pos, _ in hyps:  # positions features decode to joint positions, at most 6 frames
        assert pos.ndim == 3 and pos.shape[1:] == (21, 3) and 1 <= len(pos) <= 6


def test_ranges_of_cropped_sequences(data):
    from motionlang.evaluation.action_order import rescale_ranges
    from motionlang.evaluation.t2m.compare import _ranges, body_primitives
    rid = max(data.splits["train"], key=lambda i: len(body_primitives(data.records[i])))
    rec, n = data.records[rid], len(data.sequences[rid])
    prims = body_primitives(rec)
    full, truth = _ranges(rec, n)
    assert full == rescale_ranges([(s, e) for _, s, e in prims], rec.n_frames, n)
    assert truth == [a for a, _, _ in prims]
    # the first k frames only: the same frame numbers, cut at k; later primitives dropped
    k = full[-1][0]
    cut, cut_truth = _ranges(rec, k)
    assert cut == [(a, min(b, k)) for a, b in full if a < k]
    assert cut_truth == truth[:len(cut)] and len(cut) < len(full)


def test_model_labels_may_hold_equals_signs(tmp_path):
    from motionlang.models.options import parse_t2m, split_label
    assert split_label("full (h=128)=runs/ts.pt") == ("full (h=128)", "runs/ts.pt")
    assert split_label("runs/ts.pt") == ("ts", "runs/ts.pt")
    odd = tmp_path / "a=b.pt"
    odd.write_bytes(b"x")
    assert split_label(str(odd)) == ("a=b", str(odd))     # an existing file wins
    # a label, a model and its options in one value; without a label the row is the
    # model's stem and its options
    label, spec = parse_t2m("best of 5 (w=5)=runs/l2m.pt:method=sample,width=5")
    assert (label, spec.name, spec.options) == ("best of 5 (w=5)", "runs/l2m.pt",
                                                {"method": "sample", "width": "5"})
    label, spec = parse_t2m("runs/l2m.pt:method=sample")
    assert (label, spec.name) == ("l2m:method=sample", "runs/l2m.pt")
    assert parse_t2m(str(odd)) == ("a=b", type(spec)(str(odd)))


def test_same_parameter_oracles(data):
    """Two made-up parameter sets over the real tiny corpus: the oracle rows are the
    re-timed mean / first of the other training motions that share the item's set."""
    from types import SimpleNamespace

    from motionlang.evaluation.metrics.motion import position_metrics_mm
    from motionlang.evaluation.t2m.oracle import (
        MEAN_ROW,
        ONE_ROW,
        oracle_generations,
        oracle_table,
        parameter_key,
    )
    from motionlang.models.t2m import stretch
    train = data.splits["train"]
    kind = {rid: "walk" if k % 3 == 0 else "wave" for k, rid in enumerate(train)}
    fake = SimpleNamespace(splits=data.splits, sequences=data.sequences, features=data.features,
                           records={rid: SimpleNamespace(meta={"primitives": [
                               {"action": kind[rid], "side": None, "count": 2}]})
                               for rid in train})
    assert parameter_key(fake.records[train[0]]) == (
        (("walk", None, 2, None, None, None), "body"),)
    assert parameter_key(SimpleNamespace(meta=None)) is None
    items = eval_items(data, "train")
    kept, gens = oracle_generations(fake, items, min_group=2)
    assert [it.id for it in kept] == [it.id for it in items]     # 3+ motions of each kind
    for it in kept:
        others = [r for r in train if kind[r] == kind[it.id] and r != it.id]
        motions = [stretch(data.features.decode(data.sequences[r]), len(it.target))
                   for r in others]
        np.testing.assert_allclose(gens[MEAN_ROW][it.id], np.mean(motions, axis=0), atol=1e-9)
        np.testing.assert_allclose(gens[ONE_ROW][it.id], motions[0], atol=1e-9)
    n_wave = sum(k == "wave" for k in kind.values())   # the larger group
    kept, _ = oracle_generations(fake, items, min_group=n_wave - 1)
    assert [it.id for it in kept] == [it.id for it in items if kind[it.id] == "wave"]
    # every model row re-scored on the kept items only
    still = evaluate_model(lambda s, t: np.repeat(items[0].target[:1], t, axis=0), items,
                           data.features, None)
    rows, table = oracle_table({"still": still}, fake, *oracle_generations(fake, items,
                                                                           n_wave - 1),
                               len(items), None)
    want = position_metrics_mm([still["generated"][it.id] for it in kept],
                               [it.target for it in kept])
    assert rows["still"]["ape_local"] == pytest.approx(want["ape_local"])
    assert rows["still"]["n_items"] == len(kept) and set(rows) == {"still", MEAN_ROW, ONE_ROW}
    assert f"Only the {len(kept)} of {len(items)} test motions" in table
    with pytest.raises(MotionlangError, match="at least 1"):
        oracle_generations(fake, items, min_group=0)
    with pytest.raises(MotionlangError, match="exact parameters"):
        oracle_generations(fake, items, min_group=len(train))


def test_an_l2m_told_its_length_runs_to_it(data):
    """Asked for n frames, an L2M told its length (progress_input) runs to it even if its end
    flag says stop: no frozen tail of held frames. One not told its length ends where its
    flag says, and the rest is its last frame held."""
    from motionlang.datasets.text import Vocabulary
    from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
    from motionlang.models.t2m import generate_positions21
    vocab = Vocabulary.build([s for r in data.records.values() for s in r.annotations])
    for told in (True, False):
        torch.manual_seed(0)
        cfg = L2MConfig(vocab_size=len(vocab), n_features=66, embed_dim=8, enc_hidden=8,
                        enc_layers=1, dec_hidden=8, dec_layers=1, n_components=2,
                        dropout=0.0, max_frames=20, progress_input=told)
        l2m = LanguageToMotion(cfg, vocab, features=data.features).eval()
        with torch.no_grad():
            l2m.head.proj.bias[-1] = -30.0          # P(the motion goes on) ~ 0 at every frame
        p = generate_positions21(l2m, "a person walks forward", 9)
        assert p.shape == (9, 21, 3)
        moved = np.abs(np.diff(p, axis=0)).max(axis=(1, 2)) > 1e-9      # (8,) frame steps
        assert moved.all() if told else not moved.any()

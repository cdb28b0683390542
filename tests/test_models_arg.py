"""``--model NAME[:key=value,...]`` (``cli.models_arg``): every command that takes
text-to-motion models parses, loads and wraps them one way, and a bad option is one line,
exit code 2, before any data is read."""
from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import pytest

from motionlang.cli.main import build_parser, leaf_parsers, main
from motionlang.errors import MotionlangError


def _commands(tmp_path, spec: str) -> list[list[str]]:
    """Each command with a text-to-motion model option, given ``spec``; no data exists, so
    only the model's errors can come first."""
    none = str(tmp_path / "none")
    return [["evaluate-t2m", "--data", none, "--model", spec, "-o", str(tmp_path / "out")],
            ["evaluate-judge", "--judge", "judge", "--data", f"bandai:{none}", "--model", spec,
             "-o", str(tmp_path / "out")],
            ["evaluate", "--m2l", "m2l", "--data", none, "--t2m", spec,
             "-o", str(tmp_path / "out.json")]]


@pytest.mark.parametrize("spec, message", [
    ("l2m:beam=3", "unknown option beam (this model's options: method, width, temperature, "
                   "rerank, length_norm, map_words)"),
    ("l2m:width=two", "width: 'two' is not a valid int"),
    ("l2m:method=fast", "method must be sample, beam or mean, got 'fast'"),
    ("l2m:method=mean,rerank=m2l", "rerank ranks several motions"),
    ("l2m:width=3", "width applies to 'sample' and 'beam'"),     # unset method: the means
    ("l2m:method=sample,width", "option 'width' is not key=value"),
])
def test_bad_model_options_are_one_line(spec, message, tmp_path, capsys):
    for argv in _commands(tmp_path, spec):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, (argv, err)
        assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_no_command_has_a_family_specific_option():
    # a family's sampling options go in the model's value (--model l2m:method=sample,width=5),
    # never in options of their own
    found = [f"{leaf.prog} {s}" for leaf in leaf_parsers(build_parser())
             for action in leaf._actions for s in action.option_strings
             if s.startswith("--l2m")]
    assert not found, found


def test_the_options_are_read_from_the_model_and_checked_once():
    from motionlang.cli.models_arg import load_t2m, load_t2m_models
    from motionlang.evaluation.t2m.guo import draws
    from motionlang.models.seq2seq.config import L2MOptions
    label, t2m = load_t2m("l2m:method=sample,width=3,temperature=0.8")
    assert label == "l2m:method=sample,width=3,temperature=0.8"
    assert t2m.options == L2MOptions(method="sample", width=3, temperature=0.8)
    assert t2m.describe_options() == {"method": "sample", "width": 3, "temperature": 0.8}
    assert draws(t2m)
    # an evaluation row decodes the means unless told otherwise, and says so
    label, t2m = load_t2m("l2m")
    assert label == "l2m" and t2m.options.method == "mean" and not draws(t2m)
    with pytest.raises(MotionlangError, match="a second row named 'l2m'"):
        load_t2m_models(["l2m", "l2m"])
    assert list(load_t2m_models(["l2m", "sampled=l2m:method=sample"])) == ["l2m", "sampled"]


def test_a_reranker_is_loaded_with_the_model(tmp_path):
    from motionlang.cli.models_arg import load_t2m
    with pytest.raises(MotionlangError, match=r"--t2m l2m:method=sample,width=2,rerank=\S+: "
                                              r".*no such model file"):
        load_t2m(f"l2m:method=sample,width=2,rerank={tmp_path / 'no.pt'}", "--t2m")
    with pytest.raises(MotionlangError, match="kind l2m, not m2l"):
        load_t2m("l2m:method=sample,width=2,rerank=l2m")


def test_the_help_lists_each_familys_options_from_its_dataclass():
    from motionlang.models.seq2seq.config import L2MOptions
    for leaf in leaf_parsers(build_parser()):
        for action in leaf._actions:
            if {"--model", "--t2m"} & set(action.option_strings) and \
                    leaf.prog.split()[1].startswith("evaluate"):
                text = action.help
                assert "l2m: method (sample|beam|mean, default none)" in text, leaf.prog
                assert all(f.name in text for f in dataclasses.fields(L2MOptions))
                assert "twostream: reading (default verbs)" in text


def test_the_round_trip_needs_ranked_motions_of_the_models_own_features():
    from motionlang.evaluation.seq2seq import round_trip_model
    positions_only = SimpleNamespace(capabilities=frozenset({"reconstruct"}),
                                     model=SimpleNamespace(kind="twostream"))
    with pytest.raises(MotionlangError, match="--t2m twostream: .* a twostream model gives "
                                              "one motion"):
        round_trip_model(positions_only, "--t2m twostream")
    round_trip_model(SimpleNamespace(capabilities=frozenset({"hypotheses"}), model=None))


def test_generate_reads_the_sampling_options_of_the_model_value():
    pytest.importorskip("torch")
    import motionlang as ml
    t2m = ml.text_to_motion("l2m:method=sample,width=2")
    assert t2m.default_method() == "sample" and t2m.options.width == 2
    assert ml.text_to_motion("l2m").default_method() == "mean"   # the packaged L2M's own way
    hyps, fps = ml.generate_hypotheses("a person walks forward", "l2m:method=sample,width=2",
                                       max_frames=8, seed=0)
    mean = ml.generate_hypotheses("a person walks forward", "l2m", width=2, max_frames=8)[0]
    assert len(hyps) == 2 and len(mean) == 1 and fps == pytest.approx(12.5)
    # every option of the value reaches generation, and an explicit argument wins
    hot = ml.generate_hypotheses("a person walks forward",
                                 "l2m:method=sample,width=2,temperature=0.5", max_frames=8)[0]
    assert [s for _, s in hot] != [s for _, s in hyps]
    assert len(ml.generate_hypotheses("a person walks forward", "l2m:method=sample,width=2",
                                      width=3, max_frames=8)[0]) == 3

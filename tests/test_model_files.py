"""Model files validated before use (issue 44, item 2): each crafted or damaged checkpoint
of the audit is one line naming the file and its first bad field, refused before a model
is allocated; saving is deterministic; packaged models carry a SHA-256 checked on load."""
from __future__ import annotations

import json
import shutil
import zipfile

import numpy as np
import pytest
import torch

from helpers.seq2seq import tiny as tiny_seq2seq
from helpers.twostream import HashTokens
from helpers.twostream import tiny as tiny_twostream
from motionlang.errors import MotionlangError
from motionlang.models import registry
from motionlang.models.crbm.config import CRBMConfig
from motionlang.models.crbm.model import CRBM

torch.set_num_threads(1)


def _refused(path, *words, **kw) -> str:
    with pytest.raises(MotionlangError) as err:
        registry.load_model(path, **kw)
    msg = str(err.value)
    assert msg.startswith(f"{path}: ") and "\n" not in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("models")
    tiny_seq2seq("m2l", False).save(folder / "m2l.pt")
    tiny_seq2seq("l2m", False).save(folder / "l2m.pt")
    tiny_twostream().save(folder / "ts.pt")
    rng = np.random.default_rng(0)
    crbm = CRBM(CRBMConfig(n_hidden=4, order=2, epochs=1, batch_size=8), 3)
    crbm.fit([rng.normal(size=(20, 3))])
    crbm.save(folder / "crbm.npz")
    return folder


def _pt(files, name) -> dict:
    return torch.load(files / name, weights_only=True)


@pytest.mark.parametrize("name", ["m2l.pt", "ts.pt"])
@pytest.mark.parametrize("config", ["walk", [1, 2]])
def test_a_config_that_is_not_a_dict_is_named(files, tmp_path, name, config):
    path = tmp_path / name
    torch.save({**_pt(files, name), "config": config}, path)
    _refused(path, "damaged", f"config: expected a dict, got {type(config).__name__}",
             text_encoder=HashTokens()) if name == "ts.pt" else \
        _refused(path, "damaged", "config: expected a dict")


def test_a_config_field_of_the_wrong_type_is_named(files, tmp_path):
    d = _pt(files, "m2l.pt")
    path = tmp_path / "m2l.pt"
    torch.save({**d, "config": {**d["config"], "enc_hidden": "8"}}, path)
    _refused(path, "config.enc_hidden: expected int, got str")


@pytest.mark.parametrize("field", ["n_features", "vocab_size", "dec_hidden"])
def test_a_config_asking_for_1e9_units_is_refused_before_allocation(files, tmp_path, field):
    d = _pt(files, "m2l.pt")
    path = tmp_path / "big.pt"
    torch.save({**d, "config": {**d["config"], field: 10**9}}, path)
    _refused(path, f"M2LConfig.{field} must be an integer in 1..")


def test_a_two_stream_text_width_of_1e9_is_refused_by_its_memory(files, tmp_path):
    d = _pt(files, "ts.pt")
    path = tmp_path / "ts.pt"
    torch.save({**d, "config": {**d["config"], "text_dim": 10**9}}, path)
    _refused(path, "memory its config asks for", "MOTIONLANG_MAX_MEMORY",
             text_encoder=HashTokens())


def test_m2l_weights_labelled_as_a_two_stream_model_are_refused(files, tmp_path):
    path = tmp_path / "ts.pt"
    torch.save({**_pt(files, "m2l.pt"), "kind": "twostream"}, path)
    msg = _refused(path, "damaged twostream checkpoint", "fields of another model",
                   text_encoder=HashTokens())
    assert "newer" not in msg


def test_a_rest_pose_of_the_wrong_shape_is_named(files, tmp_path):
    d = _pt(files, "ts.pt")
    weights = {**d["state_dict"], "rest_pose": torch.zeros(5, 3)}
    path = tmp_path / "ts.pt"
    torch.save({**d, "state_dict": weights}, path)
    n = d["config"]["n_features"]
    _refused(path, f"state_dict.rest_pose: shape (5, 3), the config needs ({n},)",
             text_encoder=HashTokens())


def test_a_length_model_without_its_words_is_named(files, tmp_path):
    m = tiny_seq2seq("l2m", False)
    from motionlang.models.length import SentenceLength
    m.length_model = SentenceLength(["walk"], [3.0], 5.0, 2, 9)
    m.save(tmp_path / "l2m.pt")
    d = _pt(tmp_path, "l2m.pt")
    del d["length_model"]["words"]
    torch.save(d, tmp_path / "bad.pt")
    _refused(tmp_path / "bad.pt", "length_model.words: missing")


def test_an_unknown_tensor_is_named(files, tmp_path):
    d = _pt(files, "m2l.pt")
    path = tmp_path / "m2l.pt"
    torch.save({**d, "state_dict": {**d["state_dict"], "extra.weight": torch.zeros(2)}}, path)
    _refused(path, "state_dict.extra.weight: not a tensor of this m2l model")


@pytest.mark.parametrize("meta", ["config-str", "n_visible", "deep", "digits", "shape"])
def test_a_crafted_crbm_npz_is_one_line(files, tmp_path, meta):
    with np.load(files / "crbm.npz") as z:
        arrays = {k: z[k] for k in z.files}
    m = json.loads(str(arrays["meta"]))
    change = {"config-str": {"meta": json.dumps({**m, "config": "x"})},
              "n_visible": {"meta": json.dumps({**m, "n_visible": 10**9})},
              "deep": {"meta": "[" * 200_000 + "]" * 200_000},
              "digits": {"meta": '{"kind": ' + "9" * 5000 + "}"},
              "shape": {"A": np.zeros((2, 2))}}[meta]
    path = tmp_path / "crbm.npz"
    np.savez(path, **{**arrays, **{k: np.array(v) if isinstance(v, str) else v
                                   for k, v in change.items()}})
    want = {"config-str": "config: expected a dict", "n_visible": "n_visible: expected",
            "deep": "nested deeper", "digits": "5000 digits",
            "shape": "A: shape (2, 2)"}[meta]
    _refused(path, want)


def test_a_truncated_npz_is_one_line(files, tmp_path):
    raw = (files / "crbm.npz").read_bytes()
    path = tmp_path / "crbm.npz"
    path.write_bytes(raw[:len(raw) // 2])
    _refused(path)
    with pytest.raises(MotionlangError, match="damaged"):
        CRBM.load(path)


def test_saving_twice_gives_the_same_bytes_with_no_host_or_pid(tmp_path):
    m = tiny_seq2seq("m2l", False)
    m.save(tmp_path / "a.pt")
    m.save(tmp_path / "b.pt")
    assert (tmp_path / "a.pt").read_bytes() == (tmp_path / "b.pt").read_bytes()
    with zipfile.ZipFile(tmp_path / "a.pt") as zf:
        roots = {n.split("/")[0] for n in zf.namelist()}
    assert roots == {"archive"}


def test_every_packaged_model_has_its_digest_in_the_registry():
    for name, p in registry.PACKAGED.items():
        if p.path.is_file():   # an installation without the model files has nothing to check
            assert p.sha256 == registry.file_sha256(p.path), \
                f"{name}: run scripts/packaged_digests.py and update PACKAGED_SHA256"


def test_a_changed_byte_in_a_packaged_model_is_refused_by_name(tmp_path, monkeypatch):
    p = registry.PACKAGED["judge"]
    if not p.path.is_file():
        pytest.skip("the packaged judge is not installed")
    shutil.copy(p.path, tmp_path / "judge.pt")
    monkeypatch.setattr(registry, "PACKAGE_DIR", tmp_path)
    assert registry.resolve("judge") == tmp_path / "judge.pt"   # intact: accepted
    raw = bytearray((tmp_path / "judge.pt").read_bytes())
    raw[len(raw) // 2] ^= 0x01
    (tmp_path / "judge.pt").write_bytes(bytes(raw))
    with pytest.raises(MotionlangError) as err:
        registry.resolve("judge")
    msg = str(err.value)
    assert str(tmp_path / "judge.pt") in msg and "packaged judge" in msg and "SHA-256" in msg

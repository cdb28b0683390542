"""One contract for every model kind, each built tiny: ``save`` -> ``load`` gives bit-identical
parameters and identical outputs, through the class and through the registry (and from a
trainer's ``{"model": ...}`` file); a checkpoint of any other kind, a config field from a
newer release and a damaged file are each refused with one MotionlangError line naming the
file; outputs in eval mode are deterministic (two calls, the same result); every torch
family reads and writes through the one ``Checkpointed`` base."""
from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from helpers.seq2seq import make_batch, outputs
from helpers.seq2seq import tiny as tiny_seq2seq
from helpers.twostream import HashTokens
from helpers.twostream import tiny as tiny_twostream
from motionlang.errors import MotionlangError
from motionlang.models import registry
from motionlang.models.checkpoint import Checkpointed
from motionlang.models.crbm.ar import ARConfig, ARModel
from motionlang.models.crbm.config import PARAMS, CRBMConfig
from motionlang.models.crbm.model import CRBM
from motionlang.models.crbm.stack import CRBMStack
from motionlang.models.evaluator.config import EvaluatorConfig
from motionlang.models.evaluator.model import TextMotionEvaluator
from motionlang.models.judge.config import JudgeConfig
from motionlang.models.judge.model import MotionJudge
from motionlang.models.masked.config import MaskedConfig, MaskedOptions
from motionlang.models.masked.model import MaskedModel
from motionlang.models.retrieval.config import RetrievalConfig
from motionlang.models.retrieval.model import RetrievalModel
from motionlang.models.seq2seq.l2m import LanguageToMotion
from motionlang.models.seq2seq.m2l import MotionToLanguage
from motionlang.models.twostream.model import TwoStreamModel

torch.set_num_threads(1)
D = 4   # features per frame of the CRBM family's tiny sequences


def _sequences() -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    t = np.arange(30)[:, None] / 5.0
    return [np.sin(t + k + np.arange(D)) + 0.05 * rng.normal(size=(30, D)) for k in range(3)]


def _crbm() -> CRBM:
    return CRBM(CRBMConfig(n_hidden=6, order=2, epochs=3, batch_size=16), D).fit(_sequences())


def _stack() -> CRBMStack:
    return CRBMStack.fit(_crbm(), _sequences(),
                         CRBMConfig(n_hidden=5, order=2, epochs=3, batch_size=16, seed=1))


def _ar() -> ARModel:
    return ARModel(ARConfig(order=2), D).fit(_sequences())


class HashVectors:
    """Deterministic fake word vectors (4 per word), so the evaluator needs no GloVe."""

    dim = 4

    def __contains__(self, word: str) -> bool:
        return True

    def __getitem__(self, word: str) -> np.ndarray:
        return np.random.default_rng(sum(map(ord, word))).normal(size=4).astype(np.float32)


def _evaluator() -> TextMotionEvaluator:
    torch.manual_seed(0)
    cfg = EvaluatorConfig(motion_dim=6, drop_last=2, word_dim=4, text_hidden=4, motion_hidden=4,
                          movement_hidden=4, movement_latent=4, embed_dim=4)
    return TextMotionEvaluator(cfg, mean=np.arange(6.0), std=np.full(6, 2.0),
                               vectors=HashVectors()).eval()


def _evaluator_out(model: TextMotionEvaluator) -> np.ndarray:
    motions = [np.random.default_rng(k).normal(size=(9 + k, 6)) for k in range(2)]
    texts = model.embed_texts(["a person walks", "jump"],
                              tokens=[["a/DET", "person/NOUN", "walks/VERB"], ["jump/VERB"]])
    return np.concatenate([model.embed_motions(motions), texts])


def _judge() -> MotionJudge:
    torch.manual_seed(0)
    return MotionJudge(JudgeConfig(contents=["walk", "jog"], styles=["calm", "angry"],
                                   n_features=6, hidden=4, embed=4, layers=2, kernel=3))


def _judge_out(model: MotionJudge) -> torch.Tensor:
    x = torch.randn(2, 7, 6, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        out = model(x, torch.tensor([7, 5]))
    return torch.cat([out[k].flatten() for k in ("content", "style", "embedding")])


def _retrieval() -> RetrievalModel:
    torch.manual_seed(0)
    return RetrievalModel(RetrievalConfig(hidden=8, layers=1, heads=2, text_hidden=8, embed=4),
                          text_encoder=HashTokens())


def _retrieval_out(model: RetrievalModel) -> np.ndarray:
    motions = [np.random.default_rng(k).normal(size=(9 + k, 66)) for k in range(2)]
    return np.concatenate([model.embed_motions(motions),
                           model.embed_texts(["a person walks", "jump"])])


def _masked() -> MaskedModel:
    torch.manual_seed(0)
    return MaskedModel(MaskedConfig(width=8, depth=1, code_dim=4, codes=8, quantizers=2,
                                    hidden=8, layers=1, res_layers=1, heads=2, max_tokens=8),
                       text_encoder=HashTokens())


def _masked_out(model: MaskedModel) -> torch.Tensor:
    rows = np.random.default_rng(0).normal(size=(9, 66)).astype(np.float32)
    tokens = model.sample_tokens(["a person walks", "jump"], [3, 2], seed=0,
                                 options=MaskedOptions(steps=3))
    return torch.cat([tokens.flatten().float(),
                      torch.as_tensor(model.reconstruct(rows)).flatten()])


def _torch_params(model) -> dict[str, Any]:
    return dict(model.state_dict())


def _crbm_params(model: CRBM, prefix: str = "") -> dict[str, Any]:
    return {prefix + k: getattr(model, k) for k in (*PARAMS, "mean", "std")}


def _init() -> np.ndarray:
    return _sequences()[0][:5]


@dataclass(frozen=True)
class Kind:
    """How the contract builds, saves, reads and runs one model kind."""

    name: str                                  # the checkpoint's kind (registry key)
    cls: type
    suffix: str                                # file suffix its save expects
    build: Callable[[], Any]
    params: Callable[[Any], dict[str, Any]]    # every learnt array (and normaliser)
    run: Callable[[Any], Any]                  # an output in eval mode (array or tensor)
    load_kw: Callable[[], dict] = dict         # extra arguments of ``load``


KINDS = [
    Kind("crbm", CRBM, ".npz", _crbm, _crbm_params,
         lambda m: m.generate(_init(), 4, n_gibbs=3, seed=0)),
    Kind("crbm_stack", CRBMStack, ".npz", _stack,
         lambda m: {**_crbm_params(m.level1, "l1_"), **_crbm_params(m.level2, "l2_")},
         lambda m: m.generate(_init(), 4, n_gibbs=3, seed=0)),
    Kind("ar", ARModel, ".npz", _ar,
         lambda m: {"A": m.A, "a": m.a, "mean": m.mean, "std": m.std},
         lambda m: m.generate(_init(), 4)),
    Kind("m2l", MotionToLanguage, ".pt", lambda: tiny_seq2seq("m2l", True), _torch_params,
         lambda m: outputs(m, make_batch())),
    Kind("l2m", LanguageToMotion, ".pt", lambda: tiny_seq2seq("l2m", True), _torch_params,
         lambda m: outputs(m, make_batch())),
    Kind("twostream", TwoStreamModel, ".pt", tiny_twostream, _torch_params,
         lambda m: m.generate(["a person walks forward", "jump"], 6),
         lambda: {"text_encoder": HashTokens()}),
    Kind("evaluator", TextMotionEvaluator, ".pt", _evaluator,
         lambda m: {**m.state_dict(), "mean": m.mean, "std": m.std}, _evaluator_out,
         lambda: {"vectors": HashVectors()}),
    Kind("judge", MotionJudge, ".pt", _judge, _torch_params, _judge_out),
    Kind("retrieval", RetrievalModel, ".pt", _retrieval, _torch_params, _retrieval_out,
         lambda: {"text_encoder": HashTokens()}),
    Kind("masked", MaskedModel, ".pt", _masked, _torch_params, _masked_out,
         lambda: {"text_encoder": HashTokens()}),
]
BY_NAME = {k.name: k for k in KINDS}
IDS = [k.name for k in KINDS]
PAIRS = [(k, other) for k in KINDS for other in IDS if other != k.name]


def assert_identical(a: dict[str, Any], b: dict[str, Any]) -> None:
    assert a.keys() == b.keys()
    for key in a:
        x, y = np.asarray(a[key]), np.asarray(b[key])
        assert x.dtype == y.dtype and x.shape == y.shape, key
        assert x.tobytes() == y.tobytes(), f"{key} differs after save -> load"


def same_output(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> dict[str, tuple[Any, Path]]:
    """Every kind built tiny and saved: name -> (model in eval mode, checkpoint path)."""
    folder = tmp_path_factory.mktemp("contract")
    out = {}
    for kind in KINDS:
        model = kind.build()
        if isinstance(model, torch.nn.Module):
            model.eval()
        path = folder / f"{kind.name}{kind.suffix}"
        model.save(path)
        out[kind.name] = (model, path)
    return out


def test_every_registry_kind_is_under_contract():
    assert set(registry.families()) == set(BY_NAME)
    for kind in KINDS:
        assert registry.model_class(kind.name) is kind.cls


@pytest.mark.parametrize("kind", KINDS, ids=IDS)
@pytest.mark.parametrize("via", ["class", "registry"])
def test_save_load_is_bit_identical(kind, via, saved):
    model, path = saved[kind.name]
    if via == "class":
        loaded = kind.cls.load(path, **kind.load_kw())
    else:
        assert registry.checkpoint_kind(path) == kind.name
        loaded = registry.load_model(path, **kind.load_kw())
    assert type(loaded) is kind.cls
    if isinstance(loaded, torch.nn.Module):
        assert not loaded.training               # loaded models are in eval mode
    assert_identical(kind.params(model), kind.params(loaded))
    assert same_output(kind.run(model), kind.run(loaded))


@pytest.mark.parametrize("kind", KINDS, ids=IDS)
def test_outputs_are_deterministic_in_eval_mode(kind, saved):
    model = kind.cls.load(saved[kind.name][1], **kind.load_kw())
    first, second = kind.run(model), kind.run(model)
    assert same_output(first, second)


@pytest.mark.parametrize("kind,other", PAIRS, ids=[f"{k.name}-reads-{o}" for k, o in PAIRS])
def test_a_checkpoint_of_another_kind_is_refused_naming_the_file(kind, other, saved):
    path = saved[other][1]
    with pytest.raises(MotionlangError) as err:
        kind.cls.load(path, **kind.load_kw())
    assert str(path) in str(err.value)
    with pytest.raises(MotionlangError) as err:
        registry.load_model(path, kind=kind.name, **kind.load_kw())
    assert str(path) in str(err.value)


TORCH = [k for k in KINDS if k.suffix == ".pt"]
NPZ = [k for k in KINDS if k.suffix == ".npz"]


def _one_line_naming(err, path: Path, *words: str) -> str:
    msg = str(err.value)
    assert str(path) in msg and len(msg.splitlines()) == 1, msg
    for w in words:
        assert w in msg, msg
    return msg


def _load_both_ways(kind: Kind, path: Path) -> list:
    """The MotionlangErrors of loading ``path`` through the class and the registry."""
    errors = []
    for load in (lambda: kind.cls.load(path, **kind.load_kw()),
                 lambda: registry.load_model(path, kind=kind.name, **kind.load_kw())):
        with pytest.raises(MotionlangError) as err:
            load()
        errors.append(err)
    return errors


@pytest.mark.parametrize("kind", TORCH, ids=[k.name for k in TORCH])
def test_every_torch_family_uses_the_one_checkpoint_base(kind):
    assert issubclass(kind.cls, Checkpointed)
    copies = {"save", "load", "to_checkpoint", "from_checkpoint"} & set(vars(kind.cls))
    assert not copies, f"{kind.cls.__name__} defines its own {sorted(copies)}"
    assert kind.cls.kind == kind.name and kind.cls.config_cls is not None


@pytest.mark.parametrize("kind", TORCH, ids=[k.name for k in TORCH])
def test_a_trainer_checkpoint_loads_as_the_model(kind, saved, tmp_path):
    model, path = saved[kind.name]
    d = torch.load(path, map_location="cpu", weights_only=True)
    wrapped = tmp_path / "best.pt"
    torch.save({"model": d, "optimizer": {}, "step": 3}, wrapped)
    loaded = kind.cls.load(wrapped, **kind.load_kw())
    assert_identical(kind.params(model), kind.params(loaded))
    assert same_output(kind.run(model), kind.run(loaded))


@pytest.mark.parametrize("kind", TORCH, ids=[k.name for k in TORCH])
def test_a_checkpoint_from_a_newer_version_names_the_unknown_fields(kind, saved, tmp_path):
    """A config field this version lacks (a newer release's option) is one clear line naming
    the file and the field, not 'a damaged checkpoint'."""
    d = torch.load(saved[kind.name][1], map_location="cpu", weights_only=False)
    d["config"]["option_from_the_future"] = 1
    path = tmp_path / f"newer{kind.suffix}"
    torch.save(d, path)
    for err in _load_both_ways(kind, path):
        msg = _one_line_naming(err, path, "option_from_the_future", "newer")
        assert "damaged" not in msg


@pytest.mark.parametrize("kind", NPZ, ids=[k.name for k in NPZ])
def test_an_npz_from_a_newer_version_names_the_unknown_fields(kind, saved, tmp_path):
    src = saved[kind.name][1]
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    key = "meta" if "meta" in arrays else "l2_meta"
    meta = json.loads(str(arrays[key]))
    meta["config"]["option_from_the_future"] = 1
    arrays[key] = np.array(json.dumps(meta))
    path = tmp_path / "newer.npz"
    np.savez(path, **arrays)
    for err in _load_both_ways(kind, path):
        msg = _one_line_naming(err, path, "option_from_the_future", "newer")
        assert "damaged" not in msg


def _damaged_torch(d: dict) -> list[tuple[str, dict]]:
    first = next(iter(d["state_dict"]))
    wrong = dict(d["state_dict"])
    wrong[first] = torch.zeros(wrong[first].numel() + 1)
    return [("no weights", {k: v for k, v in d.items() if k != "state_dict"}),
            ("wrong shape", {**d, "state_dict": wrong}),
            ("config not a dict", {**d, "config": [1, 2]}),
            ("bad config value", {**d, "config": {**d["config"], next(iter(d["config"])): "x"}})]


@pytest.mark.parametrize("kind", TORCH, ids=[k.name for k in TORCH])
def test_a_damaged_torch_checkpoint_is_one_line(kind, saved, tmp_path):
    src = saved[kind.name][1]
    d = torch.load(src, map_location="cpu", weights_only=True)
    for i, (what, bad) in enumerate(_damaged_torch(d)):
        path = tmp_path / f"bad{i}.pt"
        torch.save(bad, path)
        with pytest.raises(MotionlangError) as err:
            kind.cls.load(path, **kind.load_kw())
        assert f"damaged {kind.name} checkpoint" in str(err.value), what
        _one_line_naming(err, path)
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(src.read_bytes()[:len(src.read_bytes()) // 2])
    for err in _load_both_ways(kind, truncated):
        _one_line_naming(err, truncated, "not a readable motionlang checkpoint")


@pytest.mark.parametrize("kind", NPZ, ids=[k.name for k in NPZ])
def test_a_damaged_npz_is_one_line(kind, saved, tmp_path):
    src = saved[kind.name][1]
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    missing = tmp_path / "missing.npz"
    np.savez(missing, **{k: v for k, v in arrays.items() if k not in ("A", "l2_A")})
    with pytest.raises(MotionlangError) as err:
        kind.cls.load(missing)
    _one_line_naming(err, missing, f"damaged {kind.name} checkpoint")
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(src.read_bytes()[:len(src.read_bytes()) // 2])
    with pytest.raises(MotionlangError) as err:
        kind.cls.load(truncated)
    _one_line_naming(err, truncated, "damaged")
    with pytest.raises(MotionlangError) as err:
        kind.cls.load(tmp_path / "nothing.npz")
    _one_line_naming(err, tmp_path / "nothing.npz", "no such checkpoint file")


@pytest.mark.parametrize("kind", TORCH, ids=[k.name for k in TORCH])
def test_an_option_load_does_not_take_is_the_callers_error(kind, saved):
    with pytest.raises(TypeError, match="no_such_option"):
        kind.cls.load(saved[kind.name][1], no_such_option=1)

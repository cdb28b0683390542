"""What the one checkpoint base stores besides weights: the features each model reads.

The two-stream model holds fitted ``PositionFeatures`` (old files with a bare normaliser get
them rebuilt, the same numbers); its positions go through them both ways; the judge and the
evaluator record the rows they read. The contract over every kind (round trip, newer fields,
damaged files) is ``test_model_contract.py``.
"""
from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers.mocap import synthetic_mmm
from helpers.twostream import HashTokens, tiny
from motionlang.errors import MotionlangError
from motionlang.features.angles import AnglesFeatures
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import PositionFeatures
from motionlang.models.twostream.model import DEFAULT_SECONDS, TwoStreamModel

torch.set_num_threads(1)
SENTENCE = "a person walks forward"


@pytest.fixture(scope="module")
def motion():
    return synthetic_mmm(T=201)


@pytest.fixture(scope="module")
def features(motion) -> PositionFeatures:
    return PositionFeatures().fit([motion])


def fitted_twostream(features) -> TwoStreamModel:
    m = tiny()
    m.features = features
    with torch.no_grad():
        m.rest_pose.normal_(generator=torch.Generator().manual_seed(0))
    return m.eval()


def load(path) -> TwoStreamModel:
    return TwoStreamModel.load(path, text_encoder=HashTokens())


def test_the_twostream_checkpoint_carries_its_features(features, tmp_path):
    m = fitted_twostream(features)
    m.save(tmp_path / "ts.pt")
    d = torch.load(tmp_path / "ts.pt", weights_only=True)
    assert d["features"]["kind"] == "positions" and d["features"]["config"]["fps"] == m.fps
    back = load(tmp_path / "ts.pt")
    assert isinstance(back.features, PositionFeatures) and back.fps == features.fps
    assert back.features.to_dict() == features.to_dict()
    np.testing.assert_array_equal(back.generate_positions(SENTENCE, 7),
                                  m.generate_positions(SENTENCE, 7))


@pytest.mark.parametrize("normaliser", ["Normalizer", "dict"])
def test_an_old_twostream_checkpoint_with_a_bare_normaliser_loads(normaliser, features,
                                                                  tmp_path):
    """Files from before features were stored (format 0 or 1, a normaliser alone) get
    default positions features around that normaliser: the same numbers out."""
    m = fitted_twostream(features)
    m.save(tmp_path / "new.pt")
    d = torch.load(tmp_path / "new.pt", weights_only=True)
    for key in ("features", "format", "length_model"):
        del d[key]
    if normaliser == "dict":
        d["normalizer"] = {"type": "dict", "data": {"mean": d["normalizer"]["data"]["mean"],
                                                    "std": d["normalizer"]["data"]["std"]}}
    torch.save(d, tmp_path / "old.pt")
    old = load(tmp_path / "old.pt")
    assert isinstance(old.features, PositionFeatures) and old.features.fitted
    np.testing.assert_array_equal(old.normalizer.mean, features.normalizer.mean)
    np.testing.assert_array_equal(old.normalizer.std, features.normalizer.std)
    assert old.fps == features.fps
    assert old.frames_for("walks") == round(DEFAULT_SECONDS * old.fps)
    np.testing.assert_array_equal(old.generate_positions(SENTENCE, 7),
                                  m.generate_positions(SENTENCE, 7))
    # saved again, it carries the rebuilt features
    old.save(tmp_path / "resaved.pt")
    assert torch.load(tmp_path / "resaved.pt", weights_only=True)["features"]["kind"] == \
        "positions"


def test_a_twostream_model_without_features_says_so(tmp_path):
    m = tiny().eval()
    assert not m.features.fitted
    with pytest.raises(MotionlangError, match="normaliser"):
        m.generate_positions(SENTENCE, 5)
    m.save(tmp_path / "bare.pt")
    assert torch.load(tmp_path / "bare.pt", weights_only=True)["features"] is None
    assert not load(tmp_path / "bare.pt").features.fitted
    with pytest.raises(MotionlangError, match="positions features"):
        TwoStreamModel(m.config, AnglesFeatures())


def test_setting_the_normaliser_leaves_a_shared_feature_set_alone(features):
    m = tiny()
    m.features = features
    before = features.normalizer
    m.normalizer = Normalizer().fit(np.random.default_rng(0).normal(size=(20, 66)))
    assert features.normalizer is before and m.normalizer is not before
    assert m.features.config == features.config


def test_features_from_positions_is_the_inverse_of_positions(features, motion):
    m = fitted_twostream(features)
    # a motion's own body gives exactly what the feature set encodes of the motion
    np.testing.assert_array_equal(m.features_from_positions(features.body(motion)),
                                  features.encode(motion))
    x = torch.as_tensor(features.encode(motion))
    p = m.positions(x)
    back = m.features_from_positions(p)
    assert back.shape == x.shape and back.dtype == np.float32
    np.testing.assert_allclose(m.positions(torch.as_tensor(back)), p, atol=1e-4)
    with pytest.raises(MotionlangError, match=r"\(T >= 1, 21, 3\)"):
        m.features_from_positions(np.zeros((4, 20, 3)))


def test_the_judge_records_the_features_it_reads(tmp_path):
    from motionlang.features.positions import DIM
    from motionlang.models.judge.config import JudgeConfig
    from motionlang.models.judge.model import MotionJudge, judge_rows
    cfg = JudgeConfig(contents=["walk"], styles=["calm"], hidden=4, embed=4, layers=1,
                      kernel=3, fps=10.0)
    p21 = np.random.default_rng(0).normal(size=(9, 21, 3))
    assert cfg.n_features == DIM and judge_rows(p21, 10.0, cfg).shape == (9, DIM)
    judge = MotionJudge(cfg, Normalizer().fit(judge_rows(p21, 10.0, cfg)))
    judge.save(tmp_path / "judge.pt")
    d = torch.load(tmp_path / "judge.pt", weights_only=True)
    assert d["features"]["kind"] == "positions" and d["features"]["config"]["fps"] == 10.0
    back = MotionJudge.load(tmp_path / "judge.pt")
    assert back.features.to_dict() == judge.features.to_dict()
    np.testing.assert_array_equal(back.rows(p21, 10.0), judge.rows(p21, 10.0))


def test_the_evaluator_records_the_rows_it_reads(tmp_path):
    from motionlang.models.evaluator.config import EvaluatorConfig
    from motionlang.models.evaluator.model import TextMotionEvaluator
    small = dict(word_dim=4, text_hidden=4, motion_hidden=4, movement_hidden=4,
                 movement_latent=4, embed_dim=4)
    kit = TextMotionEvaluator(EvaluatorConfig(motion_dim=251, **small))
    assert kit.features["layout"] == "h3d_vectors" and kit.features["body"] == "kit"
    assert kit.features["fps"] == 12.5 and kit.features["dim"] == 251
    assert TextMotionEvaluator(EvaluatorConfig(motion_dim=6, drop_last=2, **small)).features \
        is None
    kit.save(tmp_path / "ev.pt")
    assert TextMotionEvaluator.load(tmp_path / "ev.pt").features == kit.features
    # a file from before the entry: read off the row size
    d = torch.load(tmp_path / "ev.pt", weights_only=True)
    del d["features"]
    torch.save(d, tmp_path / "old.pt")
    assert TextMotionEvaluator.load(tmp_path / "old.pt").features == kit.features


def test_the_meta_shape_check_draws_no_numbers_and_leaves_init_as_it_was():
    import torch

    from motionlang.models.checkpoint import _meta_init_skipped
    before = torch.nn.init.normal_
    real = torch.zeros(1000)
    with torch.device("meta"), _meta_init_skipped():
        emb = torch.nn.Embedding(10, 4)              # reset_parameters: normal_ on meta
        assert emb.weight.is_meta
    with _meta_init_skipped():
        torch.nn.init.normal_(real)                   # a real tensor is still drawn into
    assert real.std() > 0.5
    assert torch.nn.init.normal_ is before



def test_loading_the_packaged_m2l_does_not_import_dynamo():
    """The point of skipping the draws: seconds of ``torch._dynamo`` on every command."""
    import subprocess
    import sys

    from motionlang.models.registry import PACKAGED
    if not PACKAGED["m2l"].path.is_file():
        pytest.skip("packaged m2l not installed")
    code = ("import sys, motionlang as ml; ml.load_model('m2l'); "
            "print('torch._dynamo' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False"

"""Text-conditioned in-betweening through the kind-neutral layer (``models.inbetween``),
the API (``ml.generate_hypotheses(..., keep=...)``) and the command line
(``generate --keep FILE:RANGES``): the ranges read by hand, the kept frames kept, and each
bad input one line naming ``--keep``."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers.mocap import synthetic_mmm
from helpers.patching import patch_everywhere
from helpers.twostream import HashTokens
from motionlang.errors import MotionlangError
from motionlang.features.positions import PositionFeatures
from motionlang.models.inbetween import Inbetweening, keep_frames, parse_keep
from motionlang.models.masked.config import MaskedConfig
from motionlang.models.masked.model import MaskedModel

torch.set_num_threads(1)


def test_parse_keep_by_hand():
    assert parse_keep("walk.bvh:0-2s,8-10s") == ("walk.bvh", [(0.0, 2.0), (8.0, 10.0)])
    assert parse_keep("C:/takes/walk.bvh:1.5-2,8-") == ("C:/takes/walk.bvh",
                                                        [(1.5, 2.0), (8.0, None)])
    assert parse_keep(("m", [(0, 1)])) == ("m", [(0.0, 1.0)])
    for bad, why in [("walk.bvh", "expected FILE:RANGES"), ("walk.bvh:2-1", "ends before"),
                     ("walk.bvh:x-2", "not a time"), ("walk.bvh:3", "not a range"),
                     ("walk.bvh:-2", "not a range"), (":0-1", "expected FILE:RANGES")]:
        with pytest.raises(MotionlangError, match=why) as err:
            parse_keep(bad)
        assert str(err.value).startswith("--keep") and len(str(err.value).splitlines()) == 1


def test_arrival_miss_by_hand():
    from motionlang.models.masked.inbetween import arrival_miss
    src = np.zeros((10, 2, 3))
    keep = np.ones(10, dtype=bool)
    keep[3:6] = False
    assert arrival_miss(src + [1.0, 0.0, 2.0], src, keep) == 0.0    # moved whole: no change
    late = src.copy()
    late[6:, :, 2] -= 0.3                 # arrives 30 cm short: the offset grows by 0.3 m
    assert np.isclose(arrival_miss(late, src, keep), 0.3)
    keep[:] = True
    keep[7:] = False                      # a gap that runs to the end constrains nothing
    assert arrival_miss(late + np.arange(10)[:, None, None], src, keep) == 0.0


def test_join_holds_feet_a_little_out_of_reach(monkeypatch):
    import motionlang.features.foot_lock as fl
    from motionlang.models.masked.inbetween import JOIN_REACH, join
    seen = []

    def spy(p21, fps, **kw):
        seen.append(kw.get("reach"))
        return np.asarray(p21, dtype=np.float64)

    patch_everywhere(monkeypatch, fl, "lock_feet", spy)
    src = np.zeros((10, 21, 3))
    keep = np.ones(10, dtype=bool)
    keep[3:6] = False
    out = join(src + 1.0, src, keep, 10.0, foot_lock=True)
    assert seen == [JOIN_REACH, JOIN_REACH] and JOIN_REACH > 1.0      # both locks
    assert np.array_equal(out[keep], src[keep])


def test_keep_frames_by_hand():
    keep = keep_frames(10, 2.0, [(0.0, 1.0), (4.0, None)])     # frames at 0, 0.5, ... 4.5 s
    assert keep.tolist() == [True, True, True, False, False, False, False, False, True, True]
    with pytest.raises(MotionlangError, match="starts after the motion ends"):
        keep_frames(10, 2.0, [(5.0, 6.0)])
    with pytest.raises(MotionlangError, match="keep every frame"):
        keep_frames(10, 2.0, [(0.0, None)])


def test_the_api_fills_between_with_the_kept_frames_kept(tmp_path):
    import motionlang as ml
    motion = synthetic_mmm(T=401)                                # 4 s at 100 Hz
    features = PositionFeatures().fit([motion])
    torch.manual_seed(0)
    model = MaskedModel(MaskedConfig(width=8, depth=1, code_dim=4, codes=8, quantizers=2,
                                     hidden=8, layers=1, res_layers=1, heads=2,
                                     max_tokens=20), features, HashTokens())
    assert isinstance(model, Inbetweening)
    hyps, fps = ml.generate_hypotheses("a person walks", model, seed=1,
                                       keep=(motion, [(0.0, 1.0), (3.0, None)]))
    p21 = features.body(motion)
    keep = keep_frames(len(p21), fps, [(0.0, 1.0), (3.0, None)])
    (out, score), = hyps
    assert fps == 12.5 and out.shape == p21.shape and np.isnan(score)
    np.testing.assert_array_equal(out[keep], p21[keep])
    assert not np.allclose(out[~keep], p21[~keep])
    path = tmp_path / "walk.bvh"
    ml.write_motion(motion, path)
    again, _ = ml.generate_hypotheses("a person walks", model, seed=1, keep=f"{path}:0-1,3-")
    assert again[0][0].shape == out.shape
    asked = []   # the API's foot lock (on by default) reaches the model's in-betweening
    real = model.inbetween
    model.inbetween = lambda *a, **kw: asked.append(kw["foot_lock"]) or real(*a, **kw)
    for lock in (True, False):
        ml.generate_hypotheses("a person walks", model, seed=1, keep=f"{path}:0-1,3-",
                               foot_lock=lock)
    ml.generate_hypotheses("a person walks", model, seed=1, keep=f"{path}:0-1,3-")
    assert asked == [True, False, True]


def test_generate_keep_on_the_command_line_is_one_line_on_bad_input(tmp_path, capsys):
    import motionlang as ml
    from motionlang.cli.main import main
    path = tmp_path / "walk.bvh"
    ml.write_motion(synthetic_mmm(T=401), path)
    out = tmp_path / "out.bvh"
    for keep, why in [(f"{path}:2-1", "ends before it starts"),
                      (f"{path}:0-1", "does not fill in motion")]:
        assert main(["generate", "a person walks", "--model", "l2m", "--keep", keep,
                     "-o", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert why in err and len(err.splitlines()) == 1 and not out.exists()

"""Goals for in-betweening (``models/masked/goal.py``): the root's track from the rows,
the goal of a gap by hand (straight and turned), gaps drawn in bounds, a goal projection
that starts as the model without it, training masked inside the gap only, in-betweening
that tells the generator where each closed gap ends, and files from before goals."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from helpers.mocap import synthetic_mmm
from helpers.twostream import HashTokens
from motionlang.features.positions import N_LOCAL, PositionFeatures
from motionlang.models.checkpoint import load_checkpoint, write_checkpoint
from motionlang.models.masked import goal as goals
from motionlang.models.masked import sampling
from motionlang.models.masked.config import MaskedConfig, MaskedOptions
from motionlang.models.masked.model import MaskedModel

torch.set_num_threads(1)
TINY = {"width": 16, "depth": 1, "code_dim": 8, "codes": 16, "quantizers": 2, "hidden": 16,
        "layers": 1, "res_layers": 1, "heads": 2, "max_tokens": 30, "window": 2.56}


@pytest.fixture(scope="module")
def features() -> PositionFeatures:
    return PositionFeatures().fit([synthetic_mmm(T=401)])


def _model(features: PositionFeatures, goal: float) -> MaskedModel:
    torch.manual_seed(0)
    return MaskedModel(MaskedConfig(**TINY, goal=goal), features, HashTokens())


def test_root_track_of_a_straight_walk_and_a_turn():
    raw = np.zeros((30, 66))
    raw[:, N_LOCAL + 1] = 0.1                      # 10 cm a frame forward
    track = goals.root_track(raw)
    assert np.allclose(track[:, 1], 0.1 * np.arange(30), atol=1e-6)
    assert np.allclose(track[:, [0, 2]], 0.0)
    raw[:, N_LOCAL + 2] = math.pi / 2 / 29          # a quarter turn left over the motion
    turned = goals.root_track(raw)
    assert math.isclose(float(turned[-1, 2]), math.pi / 2, rel_tol=1e-5)
    assert float(turned[-1, 0]) > 1.0               # it curved towards +x


def test_gap_goal_by_hand():
    # 10 cm a frame along +z, facing +z, at 10 Hz; the gap is tokens 2..4, frames 8..19
    track = np.zeros((40, 3), dtype=np.float32)
    track[:, 1] = 0.1 * np.arange(40)
    g = goals.gap_goal(track, 2, 5, 10, fps=10.0)
    assert g.shape == (10, goals.GOAL_DIM)
    assert not g[:2].any() and not g[5:].any()
    # anchors: frame 7 (last of token 1) and frame 20 (first of token 5): 1.3 m in 1.3 s
    assert np.allclose(g[2:5, :6], [[0.0, 0.65, 0.0, 1.0, 0.0, 0.0]] * 3, atol=1e-6)
    assert np.allclose(g[2:5, 6], 1.0) and np.allclose(g[2:5, 7], [1 / 6, 3 / 6, 5 / 6])
    # the same walk along +x, the body facing +x (yaw pi/2): forward in its own frame
    side = np.zeros_like(track)
    side[:, 0], side[:, 2] = track[:, 1], math.pi / 2
    assert np.allclose(goals.gap_goal(side, 2, 5, 10, 10.0), g, atol=1e-6)
    # a half turn on the spot: no displacement, sin 0, cos - 1 = -2
    spin = np.zeros_like(track)
    spin[20:, 2] = math.pi
    h = goals.gap_goal(spin, 2, 5, 10, 10.0)[3]
    assert np.allclose(h[:6], [0, 0, 0, 0, 0, -2.0], atol=1e-6)
    with pytest.raises(ValueError):
        goals.gap_goal(track, 0, 3, 10, 10.0)      # nothing kept before it


def test_kept_goal_fills_closed_gaps_only():
    track = np.zeros((40, 3), dtype=np.float32)
    track[:, 1] = 0.1 * np.arange(40)
    kept = np.array([0, 1, 1, 0, 0, 1, 0, 1, 0, 0], dtype=bool)
    g = goals.kept_goal(track, kept, 10.0)
    assert not g[0].any() and not g[8:].any()       # gaps reaching an end: no goal
    assert g[3:5, 6].all() and g[6, 6] == 1.0
    assert not g[kept].any()
    assert np.allclose(g[3:5], goals.gap_goal(track, 3, 5, 10, 10.0)[3:5])


def test_drawn_gaps_stay_inside_with_kept_tokens_around():
    gen = torch.Generator().manual_seed(0)
    assert goals.draw_gap(2, gen) is None
    lengths = set()
    for n in (3, 4, 10, 94):
        for _ in range(200):
            gap = goals.draw_gap(n, gen)
            assert gap is not None
            a, b = gap
            assert 1 <= a < b <= n - 1 and b - a <= goals.MAX_GAP
            lengths.add(b - a)
    assert max(lengths) == goals.MAX_GAP and min(lengths) == 1


def test_a_new_goal_projection_changes_nothing_until_trained(features):
    plain, with_goal = _model(features, 0.0), _model(features, 0.5)
    assert plain.generator.goal is None and with_goal.generator.goal is not None
    missing, unexpected = with_goal.load_state_dict(plain.state_dict(), strict=False)
    assert missing == ["generator.goal.weight"] and not unexpected
    tok = torch.randint(0, 16, (2, 12))
    text, valid = plain.sentence_vectors(["a", "b"]), torch.ones(2, 12, dtype=torch.bool)
    plain.eval(), with_goal.eval()
    with torch.no_grad():
        a = plain.generator(tok, text, valid)
        b = with_goal.generator(tok, text, valid, None, torch.randn(2, 12, goals.GOAL_DIM))
    assert torch.equal(a, b)
    with_goal.generator.goal.weight.data.fill_(0.1)
    with torch.no_grad():
        c = with_goal.generator(tok, text, valid, None, torch.randn(2, 12, goals.GOAL_DIM))
    assert not torch.allclose(a, c)


def test_training_masks_inside_the_gap_only(features, monkeypatch):
    model = _model(features, 1.0).set_stage("generator").train()
    rows = features.encode(synthetic_mmm(T=401))              # 50 frames: 13 tokens
    track = goals.root_track(features.normalizer.inverse(rows.astype(np.float64)))
    items = [{"tokens": np.random.default_rng(i).integers(0, 16, (13, 2)), "sentence": "x",
              "track": track} for i in range(4)]
    items.append({"tokens": np.zeros((13, 2), dtype=np.int64), "sentence": "y"})  # no track
    torch.manual_seed(0)
    batch = model.collate(items)
    assert batch["gap"][:4].any(1).all() and not batch["gap"][4].any()
    assert torch.equal(batch["goal"][..., 6] == 1.0, batch["gap"])
    seen: list[torch.Tensor] = []
    real = sampling.corrupt
    monkeypatch.setattr(sampling, "corrupt", lambda t, m, *a: seen.append(m) or real(t, m, *a))
    loss = model.loss(batch)
    assert torch.isfinite(loss["loss"])
    masked = seen[0]
    assert not (masked[:4] & ~batch["gap"][:4]).any()   # given a gap: masked inside it
    assert masked[4].any()                              # no track: masked anywhere


def test_inbetween_tells_the_generator_where_each_gap_ends(features, monkeypatch):
    model = _model(features, 0.5).set_stage("generator").eval()
    p21 = features.body(synthetic_mmm(T=401))              # 50 frames at 12.5 Hz
    keep = np.zeros(len(p21), dtype=bool)
    keep[:12], keep[36:48] = True, True                     # tokens 0-2 and 9-11 kept
    given: list[torch.Tensor] = []
    real = model.generator.forward
    monkeypatch.setattr(model.generator, "forward",
                        lambda *a, **k: given.append(a[4]) or real(*a, **k))
    out = model.inbetween("a person walks", p21, keep, options=MaskedOptions(drafts=2))
    assert out.shape == p21.shape and np.allclose(out[keep], p21[keep])
    goal = given[0]
    assert goal is not None and goal.shape[-1] == goals.GOAL_DIM
    flagged = goal[0, :, 6] == 1.0
    assert flagged[3:9].all() and not flagged[:3].any() and not flagged[9:].any()


def test_files_from_before_goals_read_without_them(features, tmp_path):
    model = _model(features, 0.0)
    path = tmp_path / "old.pt"
    model.save(path)
    state = load_checkpoint(path)
    state["config"].pop("goal")
    write_checkpoint(state, path)
    back = MaskedModel.load(path, text_encoder=HashTokens())
    assert back.config.goal == 0.0 and back.generator.goal is None


def test_each_gap_is_placed_from_the_source_where_it_begins(features):
    model = _model(features, 0.0)
    p21 = features.body(synthetic_mmm(T=401))
    raw = features.normalizer.inverse(features.encode_positions(p21).astype(np.float64))
    raw[5, N_LOCAL + 2] += 0.3                    # the draft turned 0.3 rad too far early on
    rows = features.normalizer.transform(raw)
    keep = np.ones(len(p21), dtype=bool)
    keep[20:32] = False
    out = model.decode_placed(rows, p21, keep)
    assert np.allclose(out[19:], p21[19:], atol=1e-3)      # from the gap's start: in place
    assert not np.allclose(out[6:19], p21[6:19], atol=1e-2)   # before it: as decoded
    # two gaps, and one at the start: each inner gap placed again, the first left alone
    raw[25, N_LOCAL + 2] += 0.3                   # another error, between the two gaps
    rows = features.normalizer.transform(raw)
    keep[:4], keep[36:44] = False, False
    out = model.decode_placed(rows, p21, keep)
    assert np.allclose(out[35:], p21[35:], atol=1e-3)
    assert not np.allclose(out[26:35], p21[26:35], atol=1e-2)
    assert np.allclose(out[19:25], p21[19:25], atol=1e-3)


def test_join_holds_the_feet_the_blend_would_slide(features):
    from motionlang.evaluation.metrics.physics import foot_skating
    from motionlang.features.positions import FOOT
    from motionlang.models.masked.inbetween import blend, join
    stand = np.repeat(features.body(synthetic_mmm(T=401))[:1], 40, axis=0)   # feet down
    keep = np.ones(40, dtype=bool)
    keep[10:30] = False
    stand[..., 1] -= stand[:, list(FOOT), 1].min()          # both feet on the floor
    draft = stand.copy()
    draft[30:, list(FOOT[:3]), 0] += 0.08     # its left foot arrives 8 cm off to the side
    span = slice(9, 31)
    slid = blend(draft, stand, keep)
    held = join(draft, stand, keep, 12.5, foot_lock=True)
    assert foot_skating(slid[span], 12.5) > 0.05    # the blend drags the standing feet
    assert foot_skating(held[span], 12.5) < 0.3 * foot_skating(slid[span], 12.5)
    assert np.array_equal(held[keep], stand[keep])
    assert np.array_equal(join(draft, stand, keep, 12.5), slid)



def test_blend_moves_a_gap_at_an_end_rigidly(features):
    from motionlang.models.masked.inbetween import POSE_FADE, blend
    src = features.body(synthetic_mmm(T=401))             # 50 frames
    keep = np.ones(len(src), dtype=bool)
    keep[30:] = False                                     # the last 20 frames generated
    gen = src.copy()
    gen[..., 0] += 0.5                                    # half a metre aside
    gen[:, 7, 1] += 0.3                                   # and its left wrist higher
    out = blend(gen, src, keep)
    assert np.array_equal(out[keep], src[keep])
    moved = out[30 + POSE_FADE:] - gen[30 + POSE_FADE:]   # beyond the pose fade:
    assert np.allclose(moved, [-0.5, 0.0, 0.0])           # one ground move for every joint
    steps = np.abs(np.diff(out[28:, 7, 1] - src[28:, 7, 1]))   # the wrist's offset fades in
    assert steps.max() <= 0.3 / (POSE_FADE + 1) + 1e-9
    start = keep[::-1].copy()                             # the same at the start
    first = blend(gen, src, start)[:20 - POSE_FADE] - gen[:20 - POSE_FADE]
    assert np.allclose(first, [-0.5, 0.0, 0.0])
    inner = np.ones(len(src), dtype=bool)
    inner[10:40] = False                                  # two sides: per joint, linearly
    assert np.allclose(blend(gen, src, inner)[10:40], src[10:40])

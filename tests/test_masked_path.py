"""The masked tokenizer's root path: the torch integration matches the features' own
decoding, the global-position loss sees a root that drifts while the frame loss barely
does, the foot term a foot that slides, and the decoder stage trains the decoder alone (tokens and codebooks unchanged)."""
from __future__ import annotations

import numpy as np
import torch

from helpers.mocap import synthetic_mmm
from helpers.twostream import HashTokens
from motionlang.features.positions import (
    FOOT,
    N_LOCAL,
    PositionFeatures,
    join_global,
    local_joints,
    root_step,
    root_turn,
)
from motionlang.models.masked.config import MaskedConfig
from motionlang.models.masked.model import MaskedModel
from motionlang.models.masked.path import global_errors, global_joints, root_path

torch.set_num_threads(1)
TINY = {"width": 16, "depth": 1, "code_dim": 8, "codes": 16, "quantizers": 2, "hidden": 16,
        "layers": 1, "res_layers": 1, "heads": 2, "max_tokens": 30, "window": 2.56}


def test_global_joints_match_the_features_decoding():
    rng = np.random.default_rng(0)
    raw = rng.normal(size=(3, 40, 66)) * 0.2
    want = np.stack([join_global(local_joints(r), root_step(r), root_turn(r)) for r in raw])
    got = global_joints(torch.tensor(raw)).numpy()
    assert np.allclose(got, want, atol=1e-12)
    ground, yaw = root_path(torch.tensor(raw))
    assert ground.shape == (3, 40, 2) and yaw.shape == (3, 40)
    assert float(ground[:, 0].abs().max()) == 0.0 and float(yaw[:, 0].abs().max()) == 0.0


def test_a_constant_step_error_grows_along_the_path():
    raw = torch.zeros(1, 50, 66)
    raw[..., N_LOCAL + 1] = 0.05                  # 5 cm a frame forward
    off = raw.clone()
    off[..., N_LOCAL + 1] += 0.005                # 10 % too long a stride
    miss = (global_joints(off) - global_joints(raw)).norm(dim=-1)[0, :, 0]
    assert float(miss[-1]) > 0.24 and float(miss[1]) < 0.006
    assert torch.all(miss[1:] > miss[:-1])


def test_a_sliding_foot_by_hand():
    truth = torch.zeros(1, 11, 66)
    slid = truth.clone()
    for j in FOOT:                                  # the feet move 1 cm a frame sideways
        slid[0, :, 3 * j] = 0.01 * torch.arange(11)
    frames = torch.ones(1, 11, dtype=torch.bool)
    path, foot = global_errors(slid, truth, frames, fps=10.0)
    assert torch.isclose(foot, torch.tensor(0.1))   # 0.01 m x 10 Hz
    assert torch.isclose(path, torch.tensor(0.05 * 6 / 21))   # mean over 0..0.1 m, 6 joints
    frames[0, 6:] = False                           # only the first 6 frames count
    assert torch.isclose(global_errors(slid, truth, frames, 10.0)[0],
                         torch.tensor(0.025 * 6 / 21))


def _model(path: float, foot: float = 0.0) -> MaskedModel:
    features = PositionFeatures().fit([synthetic_mmm(T=401)])
    torch.manual_seed(0)
    return MaskedModel(MaskedConfig(**TINY, path=path, foot=foot), features, HashTokens())


def test_global_terms_follow_their_weights():
    with_path, without = _model(1.0, 0.5), _model(0.0, 0.0)
    rows = with_path.features.encode(synthetic_mmm(T=401))
    for m in (with_path, without):
        m.set_stage("tokenizer").eval()
    batch = with_path.collate([{"motion": rows}])
    a, b = with_path.loss(batch), without.loss(batch)
    assert "path_m" in a and "path_m" not in b
    assert float(a["path_m"]) > 0 and float(a["foot_ms"]) > 0
    assert torch.isclose(a["loss"], b["loss"] + a["path_m"] + 0.5 * a["foot_ms"], rtol=1e-5)


def test_decoder_stage_trains_the_decoder_alone():
    model = _model(1.0)
    rows = model.features.encode(synthetic_mmm(T=401))
    model.set_stage("tokenizer").train()
    model.loss(model.collate([{"motion": rows}]))          # seeds the codebooks
    before = {k: v.clone() for k, v in model.tokenizer.state_dict().items()}
    tokens = model.tokenize([rows])[0]
    model.set_stage("decoder").train()
    trainable = {n for n, p in model.named_parameters() if p.requires_grad}
    assert trainable and all(n.startswith("tokenizer.decoder.") for n in trainable)
    opt = torch.optim.Adam([p for p in model.parameters() if p.requires_grad], lr=1e-2)
    batch = model.collate([{"motion": rows}])
    first = model.loss(batch)["loss"].item()
    for _ in range(30):
        opt.zero_grad()
        model.loss(batch)["loss"].backward()
        opt.step()
    assert model.loss(batch)["loss"].item() < first
    after = model.tokenizer.state_dict()
    changed = {k for k in before if not torch.equal(before[k], after[k])}
    assert changed and all(k.startswith("decoder.") for k in changed)
    assert np.array_equal(model.tokenize([rows])[0], tokens)


def test_files_from_before_the_terms_read_back_without_them(tmp_path):
    model = _model(1.0, 1.0)
    path = tmp_path / "m.pt"
    model.save(path)
    d = torch.load(path, weights_only=False)
    del d["config"]["path"], d["config"]["foot"]
    torch.save(d, path)
    old = MaskedModel.load(path, text_encoder=HashTokens())
    assert (old.config.path, old.config.foot) == (0.0, 0.0)
    assert MaskedModel.load(tmp_path / "m.pt", text_encoder=HashTokens()).config.path == 0.0
    model.save(path)
    assert MaskedModel.load(path, text_encoder=HashTokens()).config.foot == 1.0


def test_inbetweening_keeps_the_draft_that_arrives_closest(monkeypatch):
    import motionlang.models.masked.model as masked_model
    from motionlang.models.masked.config import MaskedOptions
    model = _model(1.0)
    model.set_stage("tokenizer").train()   # seeds the codebooks (all zero until then)
    model.loss(model.collate([{"motion": model.features.encode(synthetic_mmm(T=401))}]))
    model.set_stage("generator").eval()
    p21 = model.features.body(synthetic_mmm(T=401))[:48]
    keep = np.ones(len(p21), dtype=bool)
    keep[16:32] = False
    seen, chosen = [], []
    misses = iter([0.5, 0.2, 0.9, 0.4])          # the second draft arrives closest

    def miss(draft, source, kept):
        seen.append(draft)
        return next(misses)

    def join(generated, source, kept, fps, foot_lock=False):
        chosen.append(generated)
        return generated
    monkeypatch.setattr(masked_model, "arrival_miss", miss)
    monkeypatch.setattr(masked_model, "join", join)
    model.inbetween("a person walks", p21, keep, seed=0, options=MaskedOptions(drafts=4))
    assert len(seen) == 4 and chosen[0] is seen[1]
    assert not all(np.array_equal(seen[0], s) for s in seen[1:])   # drafts differ


def test_a_frozen_part_keeps_no_gradient_for_the_optimiser_to_decay():
    model = _model(1.0)
    model.set_stage("tokenizer").train()
    model.loss(model.collate([{"motion": model.features.encode(synthetic_mmm(T=401))}]))[
        "loss"].backward()
    assert any(p.grad is not None for p in model.tokenizer.parameters())
    model.set_stage("generator")
    assert all(p.grad is None for p in model.tokenizer.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=1e-3, weight_decay=0.5)
    before = [p.detach().clone() for p in model.tokenizer.parameters()]
    opt.zero_grad(set_to_none=False)      # as the trainer does
    opt.step()
    assert all(torch.equal(a, p) for a, p in zip(before, model.tokenizer.parameters()))

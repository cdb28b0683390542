"""``training.nadam.ChunkedNAdam``: torch's NAdam bit for bit, in pieces."""
from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from motionlang.training import nadam  # noqa: E402
from motionlang.training.trainer import OPTIMIZERS  # noqa: E402


@pytest.mark.parametrize("options", [{}, {"weight_decay": 0.1},
                                     {"weight_decay": 0.1, "decoupled_weight_decay": True}])
def test_same_numbers_as_torch_nadam_bit_for_bit(monkeypatch, options):
    monkeypatch.setattr(nadam, "CHUNK", 7)   # several pieces per parameter, a short last one
    g = torch.Generator().manual_seed(0)
    shapes = [(5, 6), (13,), (1,), (3, 4, 2)]
    ref = [torch.randn(*s, generator=g).requires_grad_() for s in shapes]
    ours = [p.detach().clone().requires_grad_() for p in ref]
    ours[0].data = ours[0].data.t().contiguous().t()   # a non-contiguous one: one piece
    ref[0].data = ref[0].data.t().contiguous().t()
    a = torch.optim.NAdam(ref, lr=0.01, **options)
    b = nadam.ChunkedNAdam(ours, lr=0.01, **options)
    for _ in range(4):
        grads = [torch.randn(*s, generator=g) for s in shapes]
        for p, q, gr in zip(ref, ours, grads):
            p.grad, q.grad = gr.clone(), gr.clone()
        a.step()
        b.step()
        assert all(torch.equal(p, q) for p, q in zip(ref, ours))
    sa, sb = a.state_dict(), b.state_dict()
    assert sa["param_groups"] == sb["param_groups"]
    for k in sa["state"]:
        assert sa["state"][k].keys() == sb["state"][k].keys()
        assert all(torch.equal(sa["state"][k][n], sb["state"][k][n]) for n in sa["state"][k])
    assert float(sb["state"][1]["step"]) == 4.0


def test_the_trainer_uses_it_and_torch_steps_what_it_cannot_cut():
    assert OPTIMIZERS["nadam"] is nadam.ChunkedNAdam
    p = torch.zeros(3, dtype=torch.complex64, requires_grad=True)
    opt = nadam.ChunkedNAdam([p], lr=0.1)
    assert not opt._simple(opt.param_groups[0])
    p.grad = torch.ones(3, dtype=torch.complex64)
    opt.step()                                   # torch's own step
    assert p.real.lt(0).all()

"""The sentence LSTM's training-time recurrence (``models/twostream/scan.py``): its
hand-written backward pass against finite differences, and its results against ``nn.LSTM``
(values and every gradient)."""
from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from motionlang.models.seq2seq.layers import last_valid_output  # noqa: E402
from motionlang.models.twostream.scan import (  # noqa: E402
    lstm_last_valid,
    lstm_scan,
)


def _r(g, *shape, scale=1.0):
    return (scale * torch.randn(*shape, generator=g, dtype=torch.float64)).requires_grad_()


def test_lstm_scan_backward_passes_gradcheck():
    g = torch.Generator().manual_seed(1)
    T, B, H = 5, 3, 4
    args = [_r(g, T, B, 4 * H), _r(g, 4 * H, H, scale=0.5)]
    assert torch.autograd.gradcheck(lstm_scan, args)
    with pytest.raises(ValueError, match="w_hh must be"):
        lstm_scan(args[0], args[1][:, :3])


def _grads(out, params):
    return torch.autograd.grad(out.square().sum(), params)


def test_lstm_stack_equals_nn_lstm_in_values_and_gradients():
    torch.manual_seed(0)
    lstm = torch.nn.LSTM(6, 5, num_layers=2, batch_first=True)
    x = torch.randn(3, 7, 6)                            # frozen features: no gradient asked
    lengths = torch.tensor([7, 2, 5])
    params = list(lstm.parameters())
    fast, ref = lstm_last_valid(lstm, x, lengths), last_valid_output(lstm, x, lengths)
    torch.testing.assert_close(fast, ref)
    for a, b in zip(_grads(fast, params), _grads(ref, params)):
        torch.testing.assert_close(a, b)
    torch.testing.assert_close(lstm_last_valid(lstm, x, None), last_valid_output(lstm, x, None))
    with torch.no_grad():
        assert torch.equal(lstm_last_valid(lstm, x, lengths), last_valid_output(lstm, x, lengths))

"""The sentence LSTM's training-time recurrence with a hand-written backward pass through
time.

Why: ``nn.LSTM`` runs fused on CPU but its backward pass always returns the gradient of its
input, and for the first layer the input is the frozen token features: a product as large as
the input projection (at the paper's size, token features of 1536 into gates of 4 x 1024),
computed and thrown away at every step of training. Here each layer's input projection is one
``F.linear`` over all steps, which autograd differentiates only in what requires a gradient;
the backward loop carries the (B, H) state gradients, and the recurrent weights' gradient is
one product over all steps at the end. (The GRUs of the pose encoder and the discriminator
gain nothing from the same treatment: their steps are bound by the matrix products either
way.) Checked against ``nn.LSTM`` and by ``gradcheck`` in the tests.

Only training uses it (:func:`use_scan`): evaluation and generation keep the torch module,
whose outputs the packaged models' fixtures pin bit for bit; the two agree to float32
rounding.
"""
from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn
from torch.autograd.function import once_differentiable

from motionlang.models.seq2seq.layers import last_valid_output


class _LSTMScan(torch.autograd.Function):
    @staticmethod
    def forward(ctx, gi, w_hh):
        T, B, H4 = gi.shape
        H = H4 // 4
        hs = gi.new_zeros(T + 1, B, H)
        cs = gi.new_zeros(T + 1, B, H)
        gates = gi.new_empty(T, B, H4)
        tanh_c = gi.new_empty(T, B, H)
        for t in range(T):
            g = torch.addmm(gi[t], hs[t], w_hh.t(), out=gates[t])   # [i | f | g | o]
            g[:, :2 * H].sigmoid_()
            g[:, 2 * H:3 * H].tanh_()
            g[:, 3 * H:].sigmoid_()
            i, f, c_in, o = g.chunk(4, dim=-1)
            torch.addcmul(i * c_in, f, cs[t], out=cs[t + 1])
            torch.mul(o, torch.tanh(cs[t + 1], out=tanh_c[t]), out=hs[t + 1])
        ctx.save_for_backward(hs, cs, gates, tanh_c, w_hh)
        return hs[1:]

    @staticmethod
    @once_differentiable
    def backward(ctx, d_out):
        hs, cs, gates, tanh_c, w_hh = ctx.saved_tensors
        T, B, H4 = gates.shape
        d_g = torch.empty_like(gates)
        d_h = torch.zeros_like(hs[0])
        d_c = torch.zeros_like(cs[0])
        for t in reversed(range(T)):
            d_h = d_h + d_out[t]
            i, f, c_in, o = gates[t].chunk(4, dim=-1)
            d_i, d_f, d_cin, d_o = d_g[t].chunk(4, dim=-1)
            torch.mul(d_h * tanh_c[t], o * (1 - o), out=d_o)
            d_c = d_c + d_h * o * (1 - tanh_c[t] * tanh_c[t])
            torch.mul(d_c * c_in, i * (1 - i), out=d_i)
            torch.mul(d_c * cs[t], f * (1 - f), out=d_f)
            torch.mul(d_c * i, 1 - c_in * c_in, out=d_cin)
            d_c = d_c * f
            d_h = d_g[t] @ w_hh
        d_w = (d_g.reshape(T * B, H4).t() @ hs[:-1].reshape(T * B, H4 // 4)
               if ctx.needs_input_grad[1] else None)
        return d_g, d_w


def lstm_scan(gi: torch.Tensor, w_hh: torch.Tensor) -> torch.Tensor:
    """One LSTM layer (``nn.LSTM``'s equations, gates [i | f | g | o]) from zero states.

    Args:
        gi: (T, B, 4H) gate pre-activations from the inputs and both biases,
            x_t @ W_ih^T + b_ih + b_hh; w_hh: (4H, H).

    Returns:
        (T, B, H) the outputs after each step; differentiable in both arguments.
    """
    if w_hh.shape != (gi.shape[-1], gi.shape[-1] // 4):
        raise ValueError(f"lstm_scan: w_hh must be {(gi.shape[-1], gi.shape[-1] // 4)}, "
                         f"got {tuple(w_hh.shape)}")
    return _LSTMScan.apply(gi, w_hh)


def use_scan(module: nn.Module) -> bool:
    """Whether ``module`` runs its recurrences here: training with gradients on."""
    return module.training and torch.is_grad_enabled()


def _last_valid(states: torch.Tensor, lengths: torch.Tensor | None) -> torch.Tensor:
    """(T, B, H) -> (B, H) the state at each sequence's last valid step."""
    if lengths is None:
        return states[-1]
    last = lengths.to(device=states.device, dtype=torch.long) - 1
    return states[last, torch.arange(states.shape[1], device=states.device)]


def lstm_last_valid(lstm: nn.LSTM, x: torch.Tensor, lengths: torch.Tensor | None
                    ) -> torch.Tensor:
    """A one-way, batch-first ``nn.LSTM`` stack over x (B, T, D) -> the last layer's output
    at each sequence's last valid step (B, H), as ``last_valid_output`` gives (which it
    calls outside training)."""
    if not use_scan(lstm) or lstm.bidirectional or lstm.proj_size or not lstm.batch_first \
            or (lstm.dropout and lstm.num_layers > 1):
        return last_valid_output(lstm, x, lengths)
    if lengths is not None and len(lengths) and not (
            1 <= int(lengths.min()) and int(lengths.max()) <= x.shape[1]):
        raise ValueError(f"sequence lengths must be in 1..{x.shape[1]} (the padded length), "
                         f"got {int(lengths.min())}..{int(lengths.max())}")
    out = x.transpose(0, 1)                                              # (T, B, D)
    for k in range(lstm.num_layers):
        w_ih, w_hh, b_ih, b_hh = (getattr(lstm, f"{n}_l{k}") for n in
                                  ("weight_ih", "weight_hh", "bias_ih", "bias_hh"))
        out = lstm_scan(F.linear(out, w_ih, b_ih + b_hh), w_hh)
    return _last_valid(out, lengths)

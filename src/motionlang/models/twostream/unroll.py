"""The two-stream decoder's unrolled recurrence as one autograd function with a hand-written
backward pass through time.

Per step t = 1 .. T-1, with the S streams' GRU cells run side by side (states h (B, S, H),
gates [r | u | n] per stream) and the Hier block folded into one affine map
(``pose.PoseDecoder``):

    x~  = target[t-1] where use[t-1] else x[t-1]          (teacher forcing)
    gi  = base[t-1] + x~ @ w_x          gh[s] = h[t-1, s] @ w_h[s] + b_h[s]
    r   = sigmoid(gi_r + gh_r)          u  = sigmoid(gi_u + gh_u)
    n   = tanh(gi_n + r * gh_n)
    h[t] = n + u * (h[t-1] - n)
    x[t] = x~ + bias + h[t] (flattened, stream by stream) @ w_o

The streams' hidden weights stay separate matrices (a batched product), not one
block-diagonal matrix: generating one motion is bound by reading the weights, and half of
a block-diagonal matrix is zeros.

Why by hand: left to autograd, every step leaves a dozen small nodes, and the weight
gradients are small matrix products summed into the same tensors T times; the backward
pass was most of a training step. Here the backward loop carries only the (B, .) state
gradients, and each weight's gradient is one large matrix product over all steps at the
end. Checked against autograd (``torch.autograd.gradcheck`` in the tests).
"""
from __future__ import annotations

import torch
from torch.autograd.function import once_differentiable


class _Unroll(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x0, h0, base, w_x, w_h, b_h, w_o, bias, target_prev, use):
        steps, B, S, H3 = base.shape
        xs_in, hs, gates, ghn = [], [h0], [], []
        x, h = x0, h0
        frames = [x0]
        for t in range(steps):
            if use is not None:
                x = torch.where(use[t], target_prev[t], x)
            xs_in.append(x)
            gi = torch.addmm(base[t].reshape(B, S * H3), x, w_x).view(B, S, H3)
            gh = torch.baddbmm(b_h[:, None], h.transpose(0, 1), w_h).transpose(0, 1)
            i_r, i_u, i_n = gi.chunk(3, dim=-1)
            h_r, h_u, h_n = gh.chunk(3, dim=-1)
            r = torch.sigmoid(i_r + h_r)
            u = torch.sigmoid(i_u + h_u)
            n = torch.tanh(i_n + r * h_n)
            h = n + u * (h - n)                                   # (B, S, H)
            x = torch.addmm(x + bias, h.reshape(B, -1), w_o)
            hs.append(h)
            gates.append(torch.cat([r, u, n], dim=-1))
            ghn.append(h_n)
            frames.append(x)
        empty = x0.new_zeros(0)
        ctx.save_for_backward(
            torch.stack(xs_in) if steps else empty, torch.stack(hs),
            torch.stack(gates) if steps else empty, torch.stack(ghn) if steps else empty,
            w_x, w_h, w_o, use if use is not None else empty)
        ctx.has_use = use is not None
        return torch.stack(frames, dim=1)

    @staticmethod
    @once_differentiable   # the saved states carry no graph: no second derivatives
    def backward(ctx, grad_frames):
        xs_in, hs, gates, ghn, w_x, w_h, w_o, use = ctx.saved_tensors
        need = ctx.needs_input_grad    # (x0, h0, base, w_x, w_h, b_h, w_o, bias, target, use)
        steps = hs.shape[0] - 1
        B, S, H = hs.shape[1:]
        g = grad_frames.unbind(1)                     # dL/dx[t] from the outputs
        w_xt, w_ht, w_ot = w_x.t(), w_h.transpose(1, 2), w_o.t()
        d_x = g[steps]
        d_h = torch.zeros_like(hs[0])
        d_gi_all, d_gh_all, d_x_out, d_target = [], [], [], []
        for t in reversed(range(steps)):
            # x[t+1] = x~ + bias + h[t+1] @ w_o
            d_x_out.append(d_x)
            d_h = d_h + (d_x @ w_ot).view(B, S, H)
            r, u, n = gates[t].chunk(3, dim=-1)
            h_prev = hs[t]
            d_n = d_h * (1 - u)
            d_u = d_h * (h_prev - n)
            d_an = d_n * (1 - n * n)
            d_ar = d_an * ghn[t] * r * (1 - r)
            d_au = d_u * u * (1 - u)
            d_gi = torch.cat([d_ar, d_au, d_an], dim=-1)          # (B, S, 3H)
            d_gh = torch.cat([d_ar, d_au, d_an * r], dim=-1)
            d_gi_all.append(d_gi)
            d_gh_all.append(d_gh)
            d_h = d_h * u + torch.bmm(d_gh.transpose(0, 1), w_ht).transpose(0, 1)
            d_xt = torch.addmm(d_x, d_gi.reshape(B, -1), w_xt)   # into x~
            if ctx.has_use:   # a forced step read the target, not x[t]
                if need[8]:
                    d_target.append(torch.where(use[t], d_xt, torch.zeros_like(d_xt)))
                d_xt = torch.where(use[t], torch.zeros_like(d_xt), d_xt)
            d_x = g[t] + d_xt
        d_x0, d_h0 = d_x, d_h
        if not steps:
            return (d_x0, d_h0, None, torch.zeros_like(w_x), torch.zeros_like(w_h),
                    w_h.new_zeros(S, w_h.shape[2]), torch.zeros_like(w_o),
                    w_o.new_zeros(w_o.shape[1]), None, None)
        # lists run from the last step to the first: flip to step order. Weight gradients
        # only when asked (a frozen decoder, e.g. refitting the sentence encoder, needs none)
        d_gi = torch.stack(d_gi_all[::-1])            # (steps, B, S, 3H)
        d_gh = torch.stack(d_gh_all[::-1]) if need[4] or need[5] else None
        d_out = torch.stack(d_x_out[::-1]) if need[6] or need[7] else None   # dL/dx[t+1]
        d_w_x = (xs_in.reshape(-1, xs_in.shape[-1]).t() @ d_gi.reshape(steps * B, -1)
                 if need[3] else None)
        per_stream = lambda a: a.reshape(steps * B, S, a.shape[-1]).transpose(0, 1)
        d_w_h = (torch.bmm(per_stream(hs[:-1]).transpose(1, 2), per_stream(d_gh))
                 if need[4] else None)
        d_w_o = hs[1:].reshape(steps * B, -1).t() @ d_out.reshape(steps * B, -1) \
            if need[6] else None
        d_target_prev = torch.stack(d_target[::-1]) if d_target else None
        return (d_x0, d_h0, d_gi if need[2] else None, d_w_x, d_w_h,
                d_gh.sum(dim=(0, 1)) if need[5] else None, d_w_o,
                d_out.sum(dim=(0, 1)) if need[7] else None, d_target_prev, None)


def unroll(x0: torch.Tensor, h0: torch.Tensor, base: torch.Tensor, w_x: torch.Tensor,
           w_h: torch.Tensor, b_h: torch.Tensor, w_o: torch.Tensor, bias: torch.Tensor,
           target_prev: torch.Tensor | None = None, use: torch.Tensor | None = None
           ) -> torch.Tensor:
    """Run the recurrence of the module docstring; differentiable in every tensor argument.

    Args:
        x0: (B, F) first frame; h0: (B, S, H) the streams' states.
        base: (T-1, B, S, 3H) input-gate terms that do not depend on the poses.
        w_x: (F, S*3H) (stream by stream, gates [r | u | n] within); w_h: (S, H, 3H);
            b_h: (S, 3H); w_o: (S*H, F); bias: (F,).
        target_prev, use: teacher forcing, (T-1, B, F) true previous frames and (T-1, B, 1)
            bool; both or neither.

    Returns:
        (B, T, F) frames, frame 0 being ``x0``.
    """
    if (target_prev is None) != (use is None):
        raise ValueError("give both target_prev and use, or neither")
    steps, B, S, H3 = base.shape
    F = x0.shape[-1]
    expected = {"x0": (x0, (B, F)), "h0": (h0, (B, S, H3 // 3)), "w_x": (w_x, (F, S * H3)),
                "w_h": (w_h, (S, H3 // 3, H3)), "b_h": (b_h, (S, H3)),
                "w_o": (w_o, (S * H3 // 3, F)), "bias": (bias, (F,))}
    if target_prev is not None and use is not None:   # both or neither (checked above)
        expected.update(target_prev=(target_prev, (steps, B, F)), use=(use, (steps, B, 1)))
    for name, (tensor, shape) in expected.items():
        if tuple(tensor.shape) != shape:
            raise ValueError(f"unroll: {name} must be {shape}, got {tuple(tensor.shape)}")
    return _Unroll.apply(x0, h0, base, w_x, w_h, b_h, w_o, bias, target_prev, use)

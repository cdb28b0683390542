"""The two-stream decoder's unrolled recurrence as one autograd function with a hand-written
backward pass through time.

Per step t = 1 .. T-1, with the streams' GRU cells fused (gate columns [r | u | n]) and the
Hier block folded into one affine map (``pose.PoseDecoder``):

    x~  = target[t-1] where use[t-1] else x[t-1]          (teacher forcing)
    gi  = base[t-1] + x~ @ w_x          gh = h[t-1] @ w_h + b_h
    r   = sigmoid(gi_r + gh_r)          u  = sigmoid(gi_u + gh_u)
    n   = tanh(gi_n + r * gh_n)
    h[t] = n + u * (h[t-1] - n)
    x[t] = x~ + bias + h[t] @ w_o

Why by hand: left to autograd, every step leaves a dozen small nodes, and the weight
gradients are small matrix products summed into the same tensors T times; the backward
pass was most of a training step. Here the backward loop carries only the (B, .) state
gradients, and each weight's gradient is one large matrix product over all steps at the
end. Checked against autograd (``torch.autograd.gradcheck`` in the tests).
"""
from __future__ import annotations

import torch


class _Unroll(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x0, h0, base, w_x, w_h, b_h, w_o, bias, target_prev, use):
        steps = base.shape[0]
        H3 = base.shape[-1]
        xs_in, hs, gates, ghn = [], [h0], [], []
        x, h = x0, h0
        frames = [x0]
        for t in range(steps):
            if use is not None:
                x = torch.where(use[t], target_prev[t], x)
            xs_in.append(x)
            gi = torch.addmm(base[t], x, w_x)
            gh = torch.addmm(b_h, h, w_h)
            i_r, i_u, i_n = gi.split(H3 // 3, dim=1)
            h_r, h_u, h_n = gh.split(H3 // 3, dim=1)
            r = torch.sigmoid(i_r + h_r)
            u = torch.sigmoid(i_u + h_u)
            n = torch.tanh(i_n + r * h_n)
            h = n + u * (h - n)
            x = torch.addmm(x + bias, h, w_o)
            hs.append(h)
            gates.append(torch.cat([r, u, n], dim=1))
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
    def backward(ctx, grad_frames):
        xs_in, hs, gates, ghn, w_x, w_h, w_o, use = ctx.saved_tensors
        steps = hs.shape[0] - 1
        H = w_h.shape[1] // 3
        g = grad_frames.unbind(1)                     # dL/dx[t] from the outputs
        w_xt, w_ht, w_ot = w_x.t(), w_h.t(), w_o.t()
        d_x = g[steps] if steps else g[0]
        d_h = torch.zeros_like(hs[0])
        d_gi_all, d_gh_all, d_x_out, d_target = [], [], [], []
        for t in reversed(range(steps)):
            # x[t+1] = x~ + bias + h[t+1] @ w_o
            d_x_out.append(d_x)
            d_h = d_h + d_x @ w_ot
            d_xt = d_x                                # into x~
            r, u, n = gates[t].split(H, dim=1)
            h_prev = hs[t]
            d_n = d_h * (1 - u)
            d_u = d_h * (h_prev - n)
            d_hprev = d_h * u
            d_an = d_n * (1 - n * n)
            d_ar = d_an * ghn[t] * r * (1 - r)
            d_au = d_u * u * (1 - u)
            d_gi = torch.cat([d_ar, d_au, d_an], dim=1)
            d_gh = torch.cat([d_ar, d_au, d_an * r], dim=1)
            d_gi_all.append(d_gi)
            d_gh_all.append(d_gh)
            d_h = torch.addmm(d_hprev, d_gh, w_ht)
            d_xt = torch.addmm(d_xt, d_gi, w_xt)
            if ctx.has_use:   # a forced step read the target, not x[t]
                d_target.append(torch.where(use[t], d_xt, torch.zeros_like(d_xt)))
                d_xt = torch.where(use[t], torch.zeros_like(d_xt), d_xt)
            d_x = g[t] + d_xt
        d_x0, d_h0 = d_x, d_h
        if not steps:
            zero = lambda *s: grad_frames.new_zeros(s)
            return (d_x0, d_h0, None, zero(*w_x.shape), zero(*w_h.shape), zero(w_h.shape[1]),
                    zero(*w_o.shape), zero(w_o.shape[1]), None, None)
        # lists run from the last step to the first: flip to step order
        d_gi = torch.stack(d_gi_all[::-1])            # (S, B, 3SH)
        d_gh = torch.stack(d_gh_all[::-1])
        d_out = torch.stack(d_x_out[::-1])            # (S, B, F): dL/dx[t+1]
        flat = lambda a: a.reshape(-1, a.shape[-1])
        d_w_x = flat(xs_in).t() @ flat(d_gi)
        d_w_h = flat(hs[:-1]).t() @ flat(d_gh)
        d_w_o = flat(hs[1:]).t() @ flat(d_out)
        d_target_prev = torch.stack(d_target[::-1]) if ctx.has_use else None
        return (d_x0, d_h0, d_gi, d_w_x, d_w_h, flat(d_gh).sum(0), d_w_o,
                flat(d_out).sum(0), d_target_prev, None)


def unroll(x0: torch.Tensor, h0: torch.Tensor, base: torch.Tensor, w_x: torch.Tensor,
           w_h: torch.Tensor, b_h: torch.Tensor, w_o: torch.Tensor, bias: torch.Tensor,
           target_prev: torch.Tensor | None = None, use: torch.Tensor | None = None
           ) -> torch.Tensor:
    """Run the recurrence of the module docstring; differentiable in every tensor argument.

    Args:
        x0: (B, F) first frame; h0: (B, SH) stacked stream states.
        base: (T-1, B, 3SH) input-gate terms that do not depend on the poses.
        w_x: (F, 3SH); w_h: (SH, 3SH); b_h: (3SH,); w_o: (SH, F); bias: (F,).
        target_prev, use: teacher forcing, (T-1, B, F) true previous frames and (T-1, B, 1)
            bool; both or neither.

    Returns:
        (B, T, F) frames, frame 0 being ``x0``.
    """
    if (target_prev is None) != (use is None):
        raise ValueError("give both target_prev and use, or neither")
    return _Unroll.apply(x0, h0, base, w_x, w_h, b_h, w_o, bias, target_prev, use)

"""NAdam whose CPU step walks the parameters in cache-sized pieces: the same arithmetic as
``torch.optim.NAdam``, element for element, so the same numbers bit for bit.

Why: torch's CPU step runs its dozen element-wise operations one after the other over each
whole parameter, and for a large tensor (the two-stream model's sentence LSTM at the paper's
size holds 19 M weights) every one of them streams the tensor and its moments from memory
again. Cut into pieces of :data:`CHUNK` elements, each piece stays in the core's cache
across those operations. The step count and the momentum product are per parameter and
the same for every piece: each piece gets a copy, and the parameter keeps the first's.

Falls back to torch's own step where the pieces do not apply (any tensor off the CPU,
complex parameters, ``foreach``, ``capturable``, ``differentiable``), or where this torch's
private single-tensor function is missing.
"""
from __future__ import annotations

from typing import Any

import torch

_single_tensor_nadam: Any
try:   # private in torch: checked bit for bit against the public step by the tests
    from torch.optim.nadam import _single_tensor_nadam
except ImportError:  # pragma: no cover - another torch
    _single_tensor_nadam = None

#: elements per piece: the piece of a parameter, its gradient, its two moments and the
#: step's temporary together fit a core's L2 cache (2 MiB on the machines we train on)
CHUNK = 1 << 17


class ChunkedNAdam(torch.optim.NAdam):
    """``torch.optim.NAdam`` (same arguments, state and ``state_dict``), faster on CPU."""

    def _simple(self, group: dict) -> bool:
        return (_single_tensor_nadam is not None and not group["foreach"]
                and not group["capturable"] and not group["differentiable"]
                and all(p.device.type == "cpu" and not torch.is_complex(p)
                        for p in group["params"]))

    @torch.no_grad()
    def step(self, closure=None):
        if not all(self._simple(g) for g in self.param_groups):
            return super().step(closure)
        loss = None
        if closure is not None:
            with torch.enable_grad():
                loss = closure()
        for group in self.param_groups:
            params, grads, avgs, sqs, mus, steps = [], [], [], [], [], []
            self._init_group(group, params, grads, avgs, sqs, mus, steps)
            pieces: list[list[torch.Tensor]] = [[], [], [], [], [], []]
            owners = []
            for p, g, m, v, mu, st in zip(params, grads, avgs, sqs, mus, steps):
                whole = not all(t.is_contiguous() for t in (p, g, m, v))
                flat = [t if whole else t.view(-1) for t in (p, g, m, v)]
                first = len(pieces[4])
                for a in range(0, 1 if whole else p.numel(), CHUNK):
                    for k in range(4):
                        pieces[k].append(flat[k] if whole else flat[k][a:a + CHUNK])
                    pieces[4].append(mu.clone())
                    pieces[5].append(st.clone())
                owners.append((mu, st, first))
            beta1, beta2 = group["betas"]
            _single_tensor_nadam(
                *pieces, beta1=beta1, beta2=beta2, lr=group["lr"],
                weight_decay=group["weight_decay"], momentum_decay=group["momentum_decay"],
                eps=group["eps"], decoupled_weight_decay=group["decoupled_weight_decay"],
                maximize=group["maximize"], capturable=False, differentiable=False,
                has_complex=False)
            for mu, st, first in owners:
                mu.copy_(pieces[4][first])
                st.copy_(pieces[5][first])
        return loss

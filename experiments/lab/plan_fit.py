"""Fitting an L2M's planner on its own (``models.seq2seq.plan.Planner``), the rest of the model frozen.

The planner only maps a sentence to a coarse plan, so it can be fitted from the sentences and
the true plans alone, without the decoder: an epoch takes seconds. Used to give a trained
plan model a planner fitted longer than its decoder was trained, or a fresh one.
"""
from __future__ import annotations

import copy
import logging
from collections.abc import Sequence

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.seq2seq.plan import Planner
from motionlang.training.collate import pad_sequences

log = logging.getLogger(__name__)


def true_plans(model, items: Sequence[dict]) -> torch.Tensor:
    """Items with ``motion`` (T, >= F) -> their plans (N, parts, 2F) as ``model`` (an L2M
    with ``plan_parts``) plans them (its first F features)."""
    F = model.config.n_features
    return torch.cat([model.plan_target(torch.as_tensor(np.asarray(it["motion"])[None, :, :F],
                                                        dtype=torch.float32),
                                        torch.tensor([len(it["motion"])]))
                      for it in items])


def _mse(planner: Planner, tokens: torch.Tensor, lengths: torch.Tensor, plans: torch.Tensor,
         batch_size: int = 512) -> float:
    planner.eval()
    with torch.no_grad():
        err = sum(float(((planner(tokens[i:i + batch_size], lengths[i:i + batch_size])
                          - plans[i:i + batch_size]) ** 2).sum())
                  for i in range(0, len(tokens), batch_size))
    return err / plans.numel()


def fit_planner(model, train: Sequence[dict], val: Sequence[dict] | None = None, *,
                epochs: int = 30, batch_size: int = 128, lr: float = 1e-3, seed: int = 0,
                fresh: bool = False) -> list[dict]:
    """Fit ``model.planner`` (an L2M with ``plan_parts``) to the plans of ``train`` items
    (``tokens``, ``motion`` in the model's normalised features) by mean squared error, with
    Adam; with ``fresh``, from new weights. Keeps the epoch with the lowest validation MSE
    (the last without ``val``). Returns one dict per epoch: ``train`` and ``val`` MSE."""
    c = model.config
    if not c.plan_parts or model.planner is None:
        raise MotionlangError("this L2M model has no planner (train it with --plan-parts)")
    if not train:
        raise MotionlangError("fit_planner needs training pairs")
    torch.manual_seed(seed)
    if fresh:
        model.planner = Planner.for_config(c)
    planner = model.planner
    sets = {}
    for name, items in (("train", train), ("val", val or [])):
        if items:
            tokens, lengths = pad_sequences([it["tokens"] for it in items], pad=c.pad_id,
                                            dtype=torch.long)
            sets[name] = (tokens, lengths, true_plans(model, items))
    opt = torch.optim.Adam(planner.parameters(), lr=lr)
    g = torch.Generator().manual_seed(seed)
    tokens, lengths, plans = sets["train"]
    history, best, best_state = [], float("inf"), None
    for epoch in range(epochs):
        planner.train()
        for idx in torch.randperm(len(tokens), generator=g).split(batch_size):
            loss = ((planner(tokens[idx], lengths[idx]) - plans[idx]) ** 2).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
        row = {"epoch": epoch + 1, "train": _mse(planner, *sets["train"])}
        if "val" in sets:
            row["val"] = _mse(planner, *sets["val"])
        history.append(row)
        log.info("planner epoch %d/%d: train MSE %.4f%s", epoch + 1, epochs, row["train"],
                 f" | val MSE {row['val']:.4f}" if "val" in row else "")
        score = row.get("val", row["train"])
        if score < best:
            best, best_state = score, copy.deepcopy(planner.state_dict())
    planner.load_state_dict(best_state)
    model.eval()
    return history

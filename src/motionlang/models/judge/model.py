"""The motion judge: dilated temporal convolutions over 21-joint position features, pooled
over time, with two heads (content, style) on a shared penultimate embedding.

Input is what every model and reader can give: global 21-joint positions (T, 21, 3),
metres, Y up (``features.joint_map.positions21``; a ``Motion`` goes through
``PositionFeatures.body``). :func:`position_rows` turns them into the position features'
layout (``features.positions``: local joints in the body frame + root steps and heading
change, at ``JudgeConfig.fps``), invariant to where the body stands and faces, and
(:func:`judge_rows`, with ``config.bones``) to its proportions; the
judge's own normaliser (fitted on its training takes) rides in its checkpoint, so a judge
never depends on the features of the model it judges.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from motionlang.errors import MotionlangError
from motionlang.features.body21 import uniform_bones21
from motionlang.features.positions import (
    PositionFeatures,
    PositionsConfig,
    floor_height,
    positions_to_rows,
)
from motionlang.models.checkpoint import (
    Checkpointed,
    pack_features,
    pack_normalizer,
    unpack_normalizer,
)
from motionlang.models.judge.config import JudgeConfig
from motionlang.models.schema import FEATURES, NORMALIZER


def resample_positions(p21: np.ndarray, fps: float, to: float) -> np.ndarray:
    """(T, J, 3) at ``fps`` -> (T', J, 3) at ``to`` Hz, linear in time, same start and
    span (T' = floor((T - 1) to / fps) + 1)."""
    p = np.asarray(p21, dtype=float)
    if abs(fps - to) < 1e-9 or len(p) < 2:
        return p
    t_src = np.arange(len(p)) / fps
    t_dst = np.arange(int(np.floor((len(p) - 1) * to / fps + 1e-9)) + 1) / to
    flat = p.reshape(len(p), -1)
    return np.stack([np.interp(t_dst, t_src, flat[:, k]) for k in range(flat.shape[1])],
                    axis=1).reshape(len(t_dst), *p.shape[1:])


def position_rows(p21: np.ndarray) -> np.ndarray:
    """Global (T, 21, 3) metres -> (T, F) un-normalised rows in ``PositionFeatures``'
    layout (``positions_to_rows``: local joints, root step and heading change), the feet
    put on y = 0 first (``floor_height``)."""
    p = np.asarray(p21, dtype=float)
    if p.ndim != 3 or p.shape[1:] != (21, 3) or not len(p) or not np.isfinite(p).all():
        raise MotionlangError(f"the judge reads finite (T >= 1, 21, 3) positions, got "
                              f"{p.shape}")
    return positions_to_rows(p - np.array([0.0, floor_height(p), 0.0]))[0]


def judge_rows(p21: np.ndarray, fps: float, config: JudgeConfig) -> np.ndarray:
    """(T, 21, 3) metres at ``fps`` -> (T', F) un-normalised rows as ``config`` reads them:
    resampled to ``config.fps``, laid on ``config.bones`` if set, :func:`position_rows`."""
    p = resample_positions(p21, fps, config.fps)
    if config.bones is not None:
        p = uniform_bones21(p, config.bones)
    return position_rows(p)


class MotionJudge(Checkpointed, nn.Module):
    """Features (B, T, F) with lengths (B,) -> content logits (B, C), style logits (B, S)
    and the penultimate embedding (B, E)."""

    kind = "judge"
    config_cls = JudgeConfig

    def __init__(self, config: JudgeConfig, normalizer=None):
        super().__init__()
        c = self.config = config
        self.normalizer = normalizer
        chans = [c.n_features] + [c.hidden] * c.layers
        self.convs = nn.ModuleList(
            nn.Conv1d(a, b, c.kernel, dilation=2 ** i, padding=(c.kernel // 2) * 2 ** i)
            for i, (a, b) in enumerate(zip(chans[:-1], chans[1:])))
        self.drop = nn.Dropout(c.dropout)
        self.embedding = nn.Linear(2 * c.hidden, c.embed)
        self.content_head = nn.Linear(c.embed, len(c.contents))
        self.style_head = nn.Linear(c.embed, len(c.styles))

    def forward(self, x: torch.Tensor, lengths: torch.Tensor) -> dict[str, torch.Tensor]:
        """x (B, T, F) normalised features, zero-padded after ``lengths`` (B,) frames."""
        mask = (torch.arange(x.shape[1], device=x.device)[None] < lengths[:, None])
        h = x.transpose(1, 2)
        for conv in self.convs:
            h = self.drop(F.relu(conv(h))) * mask[:, None]   # padding stays zero
        m = mask[:, None].float()
        mean = h.sum(-1) / m.sum(-1).clamp(min=1.0)
        peak = h.masked_fill(~mask[:, None], -1e4).amax(-1)
        e = self.drop(F.relu(self.embedding(torch.cat([mean, peak], dim=-1))))
        return {"content": self.content_head(e), "style": self.style_head(e), "embedding": e}

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """batch: ``x`` (B, T, F), ``lengths`` (B,), ``content`` (B,), ``style`` (B,) long
        label ids (-1: unknown, not counted). Loss = content CE + style CE; ``content_acc`` /
        ``style_acc``: top-1 accuracy over the known labels, left out where a batch has none
        (a loss term must be a finite number)."""
        out = self(batch["x"], batch["lengths"])
        terms = {}
        for head in ("content", "style"):
            y = batch[head]
            known = y >= 0
            if not known.any():
                terms[f"{head}_loss"] = out[head].sum() * 0.0
                continue
            terms[f"{head}_loss"] = F.cross_entropy(out[head][known], y[known])
            terms[f"{head}_acc"] = (out[head].argmax(-1) == y)[known].float().mean().detach()
        terms["loss"] = terms["content_loss"] + terms["style_loss"]
        return terms

    # -- motions in, labels and embeddings out -----------------------------------------
    def rows(self, p21: np.ndarray, fps: float) -> np.ndarray:
        """(T, 21, 3) metres at ``fps`` -> (T', F) normalised rows at ``config.fps``."""
        raw = judge_rows(p21, fps, self.config)
        return self.normalizer.transform(raw).astype(np.float32)

    @torch.no_grad()
    def judge(self, motions: Sequence[np.ndarray], fps: float, batch_size: int = 64
              ) -> dict[str, np.ndarray]:
        """Motions (each (T, 21, 3) metres at ``fps``) -> ``content`` (N, C) and ``style``
        (N, S) probabilities and ``embedding`` (N, E), whole motions, eval mode."""
        was = self.training
        self.eval()
        out: dict[str, list] = {"content": [], "style": [], "embedding": []}
        for s in range(0, len(motions), batch_size):
            rows = [torch.from_numpy(self.rows(p, fps)) for p in motions[s:s + batch_size]]
            x = nn.utils.rnn.pad_sequence(rows, batch_first=True)
            got = self(x, torch.tensor([len(r) for r in rows]))
            out["content"].append(got["content"].softmax(-1).numpy())
            out["style"].append(got["style"].softmax(-1).numpy())
            out["embedding"].append(got["embedding"].numpy())
        self.train(was)
        n = self.config
        empty = {"content": (0, len(n.contents)), "style": (0, len(n.styles)),
                 "embedding": (0, n.embed)}
        return {k: np.concatenate(v) if v else np.zeros(empty[k]) for k, v in out.items()}

    def predict(self, motions: Sequence[np.ndarray], fps: float) -> list[tuple[str, str]]:
        """The most likely (content, style) of each motion."""
        got = self.judge(motions, fps)
        return [(self.config.contents[c], self.config.styles[s]) for c, s in
                zip(got["content"].argmax(-1), got["style"].argmax(-1))]

    @property
    def features(self) -> PositionFeatures | None:
        """The layout, frame rate and normaliser of the rows the judge reads: positions
        features at ``config.fps``, feet on the floor; None before the normaliser is fitted.
        The rows themselves come from :func:`judge_rows` (resampled in time, laid on
        ``config.bones``), not from the features' ``encode``."""
        if self.normalizer is None:
            return None
        fs = PositionFeatures(PositionsConfig(fps=self.config.fps, floor=True))
        fs.normalizer = self.normalizer
        return fs

    # -- checkpoint ----------------------------------------------------------------------
    state_schema = {"normalizer": NORMALIZER, "features": FEATURES}

    def checkpoint_state(self) -> dict[str, Any]:
        return {"normalizer": pack_normalizer(self.normalizer),
                "features": pack_features(self.features)}

    @classmethod
    def from_state(cls, config: JudgeConfig, state: dict[str, Any]) -> MotionJudge:
        # the normaliser, not the features: every judge file has it, and the features
        # (from it and the config) only describe what the judge reads
        return cls(config, unpack_normalizer(state.get("normalizer")))

"""Hierarchical pose encoder and decoder of Ghosh et al. (2021), Section 3.

Encoder (per frame, then over time): each body part's columns -> linear h1; each limb's h1
concatenated with the trunk's h1 -> linear h2; the limbs of a stream concatenated (layer
norm) -> a GRU; the GRU's last hidden state is the stream embedding. Two streams (arms +
trunk -> Z_ub, legs + trunk -> Z_lb, size h each) or one whole-body stream (size 2h).
The paper's per-part layers are linear (no non-linearity before the GRU); so are ours.

Decoder, unrolled from an initial pose x_0 (B, F) for T frames: per step each stream's GRU
cell reads its columns of the current pose; the "Hier" block mirrors the encoder (hidden ->
linear to the limbs' h2 -> linear to limb h1 + trunk h1 -> per-part linear to the part's
columns; the trunk is the mean of its predictions from every limb) and gives a pose change
that is added to the current pose (residual from input pose to output pose):
``x_t = x_{t-1} + Hier(GRU(x_{t-1}, h_{t-1}))``; output frame 0 is x_0 itself.

Options beyond the paper (``TwoStreamConfig.z_every_step`` / ``time_input`` /
``progress_input``) extend the GRU input of the step that predicts frame t to
``[x_{t-1} columns, z_stream, (t - 1) / 100, (t - 1) / (T - 1)]``: with z only as the
initial state, the decoder has to carry a whole sequence of actions in a state it also
overwrites every step, and our models (h 128) lost the order of actions even when decoding a
motion from its own embedding. z and the elapsed time alone did not bring the order back; the
phase-free energy loss (``models.frame_losses.energy_loss``) with z and the progress input
did (figures in ``docs/results/twostream.md``).
"""
from __future__ import annotations

from typing import cast

import torch
from torch import nn

from motionlang.models.recurrent import last_valid_output
from motionlang.models.twostream.config import PART_NAMES, TwoStreamConfig
from motionlang.models.twostream.unroll import unroll


def _cols(config: TwoStreamConfig, parts) -> list[int]:
    return [c for p in parts for c in config.parts[p]]


class PoseEncoder(nn.Module):
    """poses (B, T, F), lengths (B,) -> {stream: (B, stream_size)} last valid GRU states."""

    def __init__(self, config: TwoStreamConfig):
        super().__init__()
        c = self.config = config
        for p in PART_NAMES:
            self.register_buffer(f"cols_{p}", torch.tensor(c.parts[p]), persistent=False)
        self.layer1 = nn.ModuleDict({p: nn.Linear(len(c.parts[p]), c.h1) for p in PART_NAMES})
        limbs = [p for p in PART_NAMES if p != "trunk"]
        self.layer2 = nn.ModuleDict({p: nn.Linear(2 * c.h1, c.h2) for p in limbs})
        self.norm = nn.ModuleDict()
        self.gru = nn.ModuleDict()
        for s, stream_limbs in c.streams().items():
            self.norm[s] = nn.LayerNorm(len(stream_limbs) * c.h2)
            self.gru[s] = nn.GRU(len(stream_limbs) * c.h2, c.stream_size, batch_first=True)

    def forward(self, poses: torch.Tensor, lengths: torch.Tensor | None = None
                ) -> dict[str, torch.Tensor]:
        l1 = {p: self.layer1[p](poses[..., getattr(self, f"cols_{p}")]) for p in PART_NAMES}
        out = {}
        for s, limbs in self.config.streams().items():
            x = torch.cat([self.layer2[p](torch.cat([l1[p], l1["trunk"]], dim=-1))
                           for p in limbs], dim=-1)
            out[s] = last_valid_output(cast(nn.GRU, self.gru[s]), self.norm[s](x), lengths)
        return out


class HierBlock(nn.Module):
    """Stream hidden states {stream: (B, stream_size)} -> pose change (B, F)."""

    order: torch.Tensor   # buffer: the PART_NAMES-order position of each feature column

    def __init__(self, config: TwoStreamConfig):
        super().__init__()
        c = self.config = config
        self.top = nn.ModuleDict({s: nn.Linear(c.stream_size, len(limbs) * c.h2)
                                  for s, limbs in c.streams().items()})
        limbs = [p for p in PART_NAMES if p != "trunk"]
        self.mid = nn.ModuleDict({p: nn.Linear(c.h2, 2 * c.h1) for p in limbs})
        self.out = nn.ModuleDict({p: nn.Linear(c.h1, len(c.parts[p])) for p in PART_NAMES})
        self.register_buffer("order", torch.tensor(
            [c for p in PART_NAMES for c in config.parts[p]]).argsort(), persistent=False)

    def forward(self, hidden: dict[str, torch.Tensor]) -> torch.Tensor:
        c = self.config
        parts, trunk = {}, []
        for s, limbs in c.streams().items():
            for p, x in zip(limbs, self.top[s](hidden[s]).split(c.h2, dim=-1)):
                limb, tr = self.mid[p](x).split(c.h1, dim=-1)
                parts[p] = self.out[p](limb)
                trunk.append(self.out["trunk"](tr))
        parts["trunk"] = torch.stack(trunk).mean(dim=0)
        # parts concatenated in PART_NAMES order, then put back in feature-column order
        return torch.cat([parts[p] for p in PART_NAMES], dim=-1)[..., self.order]


class PoseDecoder(nn.Module):
    """Stream embeddings + initial pose (B, F) -> poses (B, T, F), unrolled."""

    def __init__(self, config: TwoStreamConfig):
        super().__init__()
        c = self.config = config
        self.cells = nn.ModuleDict()
        for s, limbs in c.streams().items():
            cols = _cols(c, limbs + ("trunk",))
            self.register_buffer(f"cols_{s}", torch.tensor(sorted(cols)), persistent=False)
            extra = c.stream_size * c.z_every_step + int(c.time_input) + int(c.progress_input)
            self.cells[s] = nn.GRUCell(len(cols) + extra, c.stream_size)
        self.hier = HierBlock(config)

    def _inputs(self, x: torch.Tensor, cols: torch.Tensor, z: torch.Tensor, t: int,
                span: torch.Tensor) -> torch.Tensor:
        """The GRU input of decoding step ``t`` (1-based) for one stream: (B, D). ``span``
        (B, 1) is each sequence's T - 1 (at least 1), for the progress input."""
        c = self.config
        parts = [x[..., cols]]
        if c.z_every_step:
            parts.append(z)
        if c.time_input:
            parts.append(x.new_full((x.shape[0], 1), (t - 1) / 100.0))
        if c.progress_input:  # the step reads frame t - 1 and predicts frame t
            parts.append(((t - 1) / span).clamp(max=1.0))
        return torch.cat(parts, dim=-1) if len(parts) > 1 else parts[0]

    @staticmethod
    def _span(x0: torch.Tensor, n_frames: int, lengths: torch.Tensor | None) -> torch.Tensor:
        n = torch.full((x0.shape[0],), n_frames) if lengths is None else lengths
        return (n.to(x0) - 1).clamp(min=1.0)[:, None]

    def forward(self, z: dict[str, torch.Tensor], x0: torch.Tensor, n_frames: int,
                target: torch.Tensor | None = None, teacher_forcing: float = 0.0,
                lengths: torch.Tensor | None = None) -> torch.Tensor:
        """z {stream: (B, H)}, x0 (B, F) -> (B, n_frames, F); frame 0 is x0. ``lengths``
        (B,): each sequence's true length in a padded batch (default ``n_frames``), for
        ``progress_input``.

        Teacher forcing (training only): with probability ``teacher_forcing``, drawn per
        sequence and step, the step reads the true previous frame ``target[:, t-1]``
        (B, T, F) instead of its own previous output (the authors anneal it to 0 early).

        The Hier block is a composition of linear layers (no non-linearity, as in the
        paper), hence one affine map of the stacked stream states. It is found once per call
        by passing the unit vectors through the block (differentiably, so training works
        the same), and each of the T steps is then one matrix product instead of a dozen
        small layers: several times faster at h = 512. Likewise the streams' GRU cells run
        as one (:meth:`_fused_gates`), and the recurrence is one autograd function with its
        own backward pass (``unroll.unroll``). :meth:`unroll_layered` is the literal
        layer-by-layer version with ``nn.GRUCell`` (the reference the tests compare with)."""
        streams = list(self.cells)
        H = self.config.stream_size
        probe = torch.cat([torch.zeros(1, H * len(streams)),
                           torch.eye(H * len(streams))]).to(x0)
        out = self.hier({s: probe[:, k * H:(k + 1) * H] for k, s in enumerate(streams)})
        bias, weight = out[0], out[1:] - out[0]               # (F,), (S*H, F)
        w_x, w_h, b_h, gate_base = self._fused_gates(z, x0, n_frames, lengths)
        h0 = torch.stack([z[s] for s in streams], dim=1)      # (B, S, H)
        target_prev = use = None
        if target is not None and teacher_forcing > 0:
            use = torch.rand(n_frames - 1, x0.shape[0], 1, device=x0.device) < teacher_forcing
            target_prev = target[:, :n_frames - 1].transpose(0, 1)
        return unroll(x0, h0, gate_base, w_x, w_h, b_h, weight, bias, target_prev, use)

    def _fused_gates(self, z: dict[str, torch.Tensor], x0: torch.Tensor, n_frames: int,
                     lengths: torch.Tensor | None):
        """The streams' GRU cells side by side: per step, input gates
        ``x @ w_x + base[t - 1]`` and hidden gates ``h[:, s] @ w_h[s] + b_h[s]`` for the
        states h (B, S, H), gate columns [r | u | n] per stream.

        Returns:
            w_x (F, S*3H): each cell's pose-column weights placed at its feature columns
            (zero elsewhere), stream by stream; w_h (S, H, 3H); b_h (S, 3H); base
            (n_frames - 1, B, S, 3H): the input bias plus what z (``z_every_step``) and the
            clocks add, which do not depend on the unrolled poses: computed for all steps
            at once, so that each step is two matrix products and a few element-wise ops.
        """
        c = self.config
        H, F, B = c.stream_size, c.n_features, x0.shape[0]
        steps = torch.arange(1, n_frames, dtype=x0.dtype, device=x0.device)   # t = 1..T-1
        clocks = []
        if c.time_input:
            clocks.append(((steps - 1) / 100.0)[:, None].expand(-1, B))
        if c.progress_input:
            span = self._span(x0, n_frames, lengths)[:, 0]                    # (B,)
            clocks.append(((steps - 1)[:, None] / span[None]).clamp(max=1.0))
        w_x, base = [], []
        for s, module in self.cells.items():
            cell = cast(nn.GRUCell, module)
            cols = getattr(self, f"cols_{s}")
            n = len(cols)
            w = cell.weight_ih                                   # (3H, n + [H] + clocks)
            w_x.append(w.new_zeros(3 * H, F).index_copy(1, cols, w[:, :n]))
            g = cell.bias_ih.expand(B, -1)
            if c.z_every_step:
                g = torch.addmm(g, z[s], w[:, n:n + H].t())
            g = g.expand(max(n_frames - 1, 0), B, 3 * H)
            if clocks:
                g = g + torch.stack(clocks, dim=-1) @ w[:, w.shape[1] - len(clocks):].t()
            base.append(g)
        cells = [cast(nn.GRUCell, cell) for cell in self.cells.values()]
        return (torch.cat(w_x).t(), torch.stack([cell.weight_hh.t() for cell in cells]),
                torch.stack([cell.bias_hh for cell in cells]), torch.stack(base, dim=2))

    def unroll_layered(self, z: dict[str, torch.Tensor], x0: torch.Tensor, n_frames: int,
                       lengths: torch.Tensor | None = None) -> torch.Tensor:
        """Same as :meth:`forward`, running the Hier block layer by layer at every step."""
        h = dict(z)
        x = x0
        frames = [x0]
        span = self._span(x0, n_frames, lengths)
        for t in range(1, n_frames):
            h = {s: cell(self._inputs(x, getattr(self, f"cols_{s}"), z[s], t, span), h[s])
                 for s, cell in self.cells.items()}
            x = x + self.hier(h)
            frames.append(x)
        return torch.stack(frames, dim=1)

"""Motion-to-language seq2seq model (Plappert, Mandery & Asfour 2018, Section 4.1).

Encoder: bidirectional GRUs over motion features (paper: 2 x 64 per direction); context =
last output of the last layer, both directions concatenated. Decoder: GRUs (paper: 2 x 128)
each fed the context, the embedding of the previous word (64-d) and the previous layer's
output; a softmax over the vocabulary reads every decoder layer's output. Optional
additive attention (``attention=True``): the top decoder layer's output queries the encoder
outputs and the attended vector joins the softmax input.

The decoder is driven word by word through :meth:`MotionToLanguage.step` so that
``motionlang.models.seq2seq.decode.beam`` can search it without knowing the model.
"""
from __future__ import annotations

from typing import Any

import torch
from torch import nn
from torch.nn import functional as F

from motionlang.models.seq2seq.checkpoint import Seq2SeqCheckpointed
from motionlang.models.seq2seq.config import M2LConfig  # noqa: F401 (re-exported)
from motionlang.models.seq2seq.layers import AdditiveAttention, BiGRUEncoder, StackedDecoder


class MotionToLanguage(Seq2SeqCheckpointed, nn.Module):
    """Motion features (B, T, F) -> next-word logits (B, L, V).

    ``vocab`` (a ``Vocabulary`` or a token list) and ``normalizer`` ride along in the
    checkpoint so that :meth:`load` alone rebuilds a usable model.
    """

    kind = "m2l"
    config_cls = M2LConfig

    def __init__(self, config: M2LConfig, vocab: Any = None, normalizer: Any = None,
                 features: Any = None):
        super().__init__()
        c = self.config = config
        self.vocab, self.normalizer, self.features = vocab, normalizer, features
        self.encoder = BiGRUEncoder(c.n_features, c.enc_hidden, c.enc_layers, c.dropout)
        ctx = self.encoder.out_dim
        self.embed = nn.Embedding(c.vocab_size, c.embed_dim, padding_idx=c.pad_id)
        self.decoder = StackedDecoder(ctx + c.embed_dim, c.dec_hidden, c.dec_layers, c.dropout)
        out_in = self.decoder.out_dim
        self.attn = None
        if c.attention:
            self.attn = AdditiveAttention(c.dec_hidden, ctx, c.attn_dim)
            out_in += ctx
        self.drop = nn.Dropout(c.dropout)
        self.out = nn.Linear(out_in, c.vocab_size)

    # -- encoder / decoder -------------------------------------------------------------
    def encode(self, motion: torch.Tensor, lengths: torch.Tensor) -> dict:
        """motion (B, T, F), lengths (B,) -> decoder state with ``h`` (B, layers, H) zeros,
        ``context`` (B, C), encoder ``memory`` (B, T, C) and its ``mask`` (B, T)."""
        context, memory, mask = self.encoder(motion, lengths)
        B = motion.shape[0]
        h = motion.new_zeros(B, self.config.dec_layers, self.config.dec_hidden)
        return {"h": h, "context": context, "memory": memory, "mask": mask}

    def _decode(self, state: dict, tokens: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """tokens (B, L) previous words -> logits (B, L, V), new hidden (B, layers, H)."""
        L = tokens.shape[1]
        emb = self.drop(self.embed(tokens))
        ctx = state["context"].unsqueeze(1).expand(-1, L, -1)
        outs, h = self.decoder(torch.cat([ctx, emb], dim=-1), state["h"])
        if self.attn is not None:
            top = outs[..., -self.config.dec_hidden:]
            att, _ = self.attn(top, state["memory"], state["mask"])
            outs = torch.cat([outs, att], dim=-1)
        return self.out(outs), h

    def forward(self, motion: torch.Tensor, lengths: torch.Tensor,
                tokens_in: torch.Tensor) -> torch.Tensor:
        """Teacher forcing: tokens_in (B, L) = SOS w1 ... -> logits (B, L, V)."""
        logits, _ = self._decode(self.encode(motion, lengths), tokens_in)
        return logits

    def step(self, state: dict, prev_tokens: torch.Tensor) -> tuple[torch.Tensor, dict]:
        """One decoding step: prev_tokens (N,) -> log probabilities (N, V), new state."""
        logits, h = self._decode(state, prev_tokens.unsqueeze(1))
        return F.log_softmax(logits[:, 0].float(), dim=-1), {**state, "h": h}

    def loss(self, batch: dict) -> dict[str, torch.Tensor]:
        """batch: ``motion`` (B, T, F), ``motion_lengths`` (B,), ``tokens`` (B, L) long =
        SOS w1 .. wn EOS padded with PAD. Returns token-mean cross-entropy as ``loss``."""
        tokens = batch["tokens"]
        logits = self(batch["motion"], batch["motion_lengths"], tokens[:, :-1])
        target = tokens[:, 1:]
        ce = F.cross_entropy(logits.reshape(-1, logits.shape[-1]), target.reshape(-1),
                             ignore_index=self.config.pad_id)
        valid = target != self.config.pad_id
        acc = (logits.argmax(-1) == target)[valid].float().mean()
        return {"loss": ce, "token_acc": acc.detach()}

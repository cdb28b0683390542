"""Tiny M2L and L2M models and data for them: a padded batch, a model of either kind, its
outputs as one tensor, and eight (motion, sentence) items of two kinds."""
from __future__ import annotations

import numpy as np
import torch

from motionlang.models.seq2seq.l2m import L2MConfig, LanguageToMotion
from motionlang.models.seq2seq.m2l import M2LConfig, MotionToLanguage

F_DIM, V = 5, 9      # features per frame; vocabulary with PAD SOS EOS UNK + 5 words


def make_batch(seed: int = 0, B: int = 4) -> dict:
    g = torch.Generator().manual_seed(seed)
    m_len = torch.tensor([7, 5, 6, 3][:B])
    t_len = torch.tensor([5, 4, 3, 5][:B])          # SOS w.. EOS
    motion = torch.zeros(B, int(m_len.max()), F_DIM)
    tokens = torch.zeros(B, int(t_len.max()), dtype=torch.long)
    for b in range(B):
        motion[b, :m_len[b]] = torch.randn(int(m_len[b]), F_DIM, generator=g)
        words = torch.randint(4, V, (int(t_len[b]) - 2,), generator=g)
        tokens[b, :t_len[b]] = torch.cat([torch.tensor([1]), words, torch.tensor([2])])
    return {"motion": motion, "motion_lengths": m_len, "tokens": tokens, "token_lengths": t_len}


def tiny(kind: str, attention: bool, dropout: float = 0.0, **l2m_options):
    torch.manual_seed(0)
    if kind == "m2l":
        cfg = M2LConfig(n_features=F_DIM, vocab_size=V, enc_hidden=8, enc_layers=2,
                        dec_hidden=16, dec_layers=2, embed_dim=8, dropout=dropout,
                        attention=attention, attn_dim=8, max_len=6)
        return MotionToLanguage(cfg, vocab=[f"w{i}" for i in range(V)],
                                normalizer={"mean": np.zeros(F_DIM), "std": np.ones(F_DIM)})
    cfg = L2MConfig(vocab_size=V, n_features=F_DIM, embed_dim=8, enc_hidden=8, enc_layers=1,
                    dec_hidden=16, dec_layers=3, n_components=3, dropout=dropout,
                    attention=attention, attn_dim=8, max_frames=10, **l2m_options)
    return LanguageToMotion(cfg, vocab=[f"w{i}" for i in range(V)])


def outputs(model, batch) -> torch.Tensor:
    model.eval()
    with torch.no_grad():
        if model.kind == "m2l":
            return model(batch["motion"], batch["motion_lengths"], batch["tokens"][:, :-1])
        p = model(batch["tokens"], batch["token_lengths"], batch["motion"])
        return torch.cat([p.logit_pi.flatten(), p.mu.flatten(), p.log_sigma.flatten(),
                          p.active_logit.flatten()])


WORDS = [f"w{i}" for i in range(V)]


def items(seed=0):
    """Two kinds of motion (rising / falling first feature), each with its sentence."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(8):
        up = i % 2 == 0
        T = 6 + i % 3
        ramp = np.linspace(0, 1, T) if up else np.linspace(1, 0, T)
        motion = 3.0 + 2.0 * rng.normal(size=(T, F_DIM)) * 0.05
        motion[:, 0] += 2.0 * ramp
        tokens = [1, 4, 5, 6, 7, 2] if up else [1, 8, 7, 6, 5, 4, 2]
        out.append({"motion": motion.astype(np.float32), "tokens": tokens})
    return out

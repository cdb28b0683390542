"""The forward pass of a BERT or MPNet sentence encoder in plain torch, from a Hugging Face
model folder (``config.json``, ``model.safetensors`` or ``pytorch_model.bin``,
``tokenizer.json``), without the ``transformers`` library.

Why: ``transformers`` imports ``torch._dynamo`` (and makes torch's compile cache folder) as
its model code loads, which costs every command that reads a sentence through an encoder
(the two-stream and masked models, the retrieval model's text side, the word map) start-up
time it never uses. The encoders motionlang ships or installs are a BERT (MiniLM-L6) and an
MPNet (all-mpnet-base-v2); both are a stack of post-norm transformer layers, so their
inference is short to state. Anything else still goes through ``transformers``
(``text_tokens.TransformerTokens`` chooses).

The architectures, as published (Devlin et al. 2019; Song et al. 2020) and as their
reference implementation lays out the weights:

* **BERT**: word + absolute position + token-type (0) embeddings, LayerNorm; per layer
  self-attention (scaled dot product, padded keys masked), dense, residual, LayerNorm; a
  GELU (erf) feed-forward, residual, LayerNorm.
* **MPNet**: word + position embeddings, positions counted from ``padding_idx + 1`` over
  the real tokens, LayerNorm; the same layers, with a learnt bias per head on the attention
  scores by bucketed relative position (T5's buckets: 32, half per direction, exact below
  8, logarithmic up to a distance of 128), shared by all layers.

Tokenisation is the folder's own ``tokenizer.json`` through the ``tokenizers`` library (the
Rust tokenizer ``transformers`` itself uses), truncated to ``max_length`` tokens.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import torch
import torch.nn.functional as F

from motionlang.errors import MotionlangError

#: model types this module runs
TYPES = ("bert", "mpnet")


def model_type(folder: Path) -> str:
    """The ``model_type`` of a Hugging Face folder's ``config.json`` ("" if unreadable)."""
    try:
        return str(json.loads((folder / "config.json").read_text()).get("model_type", ""))
    except (OSError, ValueError, AttributeError):
        return ""


def runs(folder: Path) -> bool:
    """Whether this module can run the model in ``folder`` (its type, weights, tokenizer)."""
    return model_type(folder) in TYPES and (folder / "tokenizer.json").is_file() and any(
        (folder / n).is_file() for n in ("model.safetensors", "pytorch_model.bin"))


class PlainEncoder:
    """A BERT or MPNet encoder's hidden states, by :meth:`hidden_states`.

    Args:
        folder: a Hugging Face model folder (see the module docstring).
        max_length: tokens kept per sentence (special tokens included).
    """

    def __init__(self, folder: str | Path, max_length: int = 128):
        folder = Path(folder)
        try:
            self.config = json.loads((folder / "config.json").read_text())
            from tokenizers import Tokenizer
            self.tokenizer = Tokenizer.from_file(str(folder / "tokenizer.json"))
            weights = _weights(folder)
        except Exception as exc:   # noqa: BLE001 (a damaged file, whichever library read it)
            raise MotionlangError(f"{folder}: cannot load the text model: {exc}") from None
        self.kind = str(self.config.get("model_type"))
        if self.kind not in TYPES:
            raise MotionlangError(f"{folder}: a {self.kind!r} model; this encoder runs "
                                  f"{', '.join(TYPES)}")
        c = self.config
        self.n_layers = int(c["num_hidden_layers"])
        self.hidden_size = int(c["hidden_size"])
        self.heads = int(c["num_attention_heads"])
        self.eps = float(c.get("layer_norm_eps", 1e-12 if self.kind == "bert" else 1e-5))
        self.pad_id = int(c.get("pad_token_id", 0 if self.kind == "bert" else 1))
        self.tokenizer.no_padding()
        self.tokenizer.enable_truncation(max_length)
        prefix = next((p for p in ("bert.", "mpnet.") if any(k.startswith(p) for k in weights)),
                      "")
        self.w = {k[len(prefix):]: v.to(torch.float32) for k, v in weights.items()
                  if k.startswith(prefix)}
        missing = [k for k in self._needed() if k not in self.w]
        if missing:
            raise MotionlangError(f"{folder}: the weights lack {missing[0]} (and "
                                  f"{len(missing) - 1} more)")

    def _needed(self) -> list[str]:
        names = ["embeddings.word_embeddings.weight", "embeddings.position_embeddings.weight",
                 "embeddings.LayerNorm.weight"]
        if self.kind == "bert":
            names.append("embeddings.token_type_embeddings.weight")
        else:
            names.append("encoder.relative_attention_bias.weight")
        for i in range(self.n_layers):
            names += [f"encoder.layer.{i}.{n}.weight" for n in self._layer_names()]
        return names

    def _layer_names(self) -> tuple[str, ...]:
        if self.kind == "bert":
            return ("attention.self.query", "attention.self.key", "attention.self.value",
                    "attention.output.dense", "attention.output.LayerNorm",
                    "intermediate.dense", "output.dense", "output.LayerNorm")
        return ("attention.attn.q", "attention.attn.k", "attention.attn.v", "attention.attn.o",
                "attention.LayerNorm", "intermediate.dense", "output.dense",
                "output.LayerNorm")

    def tokenize(self, sentences: list[str]) -> tuple[torch.Tensor, torch.Tensor]:
        """Token ids (B, L) long, padded with the pad id, and the mask (B, L) of real
        tokens."""
        encoded = self.tokenizer.encode_batch(list(sentences))
        length = max(len(e.ids) for e in encoded)
        ids = torch.full((len(encoded), length), self.pad_id, dtype=torch.long)
        mask = torch.zeros((len(encoded), length), dtype=torch.bool)
        for b, e in enumerate(encoded):
            ids[b, :len(e.ids)] = torch.tensor(e.ids, dtype=torch.long)
            mask[b, :len(e.ids)] = True
        return ids, mask

    @torch.no_grad()
    def hidden_states(self, sentences: list[str]) -> tuple[list[torch.Tensor], torch.Tensor]:
        """The embedding output and each layer's output, ``n_layers + 1`` tensors (B, L, H),
        and the mask (B, L) of real tokens."""
        ids, mask = self.tokenize(sentences)
        w = self.w
        if self.kind == "bert":
            positions = torch.arange(ids.shape[1])
            x = (w["embeddings.word_embeddings.weight"][ids]
                 + w["embeddings.position_embeddings.weight"][positions][None]
                 + w["embeddings.token_type_embeddings.weight"][0])
            bias = None
        else:
            positions = torch.cumsum(mask.long(), dim=1) * mask + self.pad_id
            x = (w["embeddings.word_embeddings.weight"][ids]
                 + w["embeddings.position_embeddings.weight"][positions])
            bias = self._position_bias(ids.shape[1])
        x = self._norm(x, "embeddings.LayerNorm")
        # padded keys get no attention: -inf would give NaN rows only where nothing is real
        scores_mask = torch.where(mask, 0.0, torch.finfo(torch.float32).min)[:, None, None, :]
        if bias is not None:
            scores_mask = scores_mask + bias
        states = [x]
        for i in range(self.n_layers):
            x = self._layer(x, scores_mask, f"encoder.layer.{i}.")
            states.append(x)
        return states, mask

    def _linear(self, x: torch.Tensor, name: str) -> torch.Tensor:
        return F.linear(x, self.w[name + ".weight"], self.w.get(name + ".bias"))

    def _norm(self, x: torch.Tensor, name: str) -> torch.Tensor:
        return F.layer_norm(x, (x.shape[-1],), self.w[name + ".weight"],
                            self.w.get(name + ".bias"), self.eps)

    def _layer(self, x: torch.Tensor, scores_mask: torch.Tensor, at: str) -> torch.Tensor:
        names = self._layer_names()
        q, k, v, o, norm1, inner, outer, norm2 = (at + n for n in names)
        B, L, H = x.shape
        d = H // self.heads

        def heads(t: torch.Tensor) -> torch.Tensor:
            return t.view(B, L, self.heads, d).transpose(1, 2)      # (B, heads, L, d)

        scores = heads(self._linear(x, q)) @ heads(self._linear(x, k)).transpose(-1, -2)
        probs = torch.softmax(scores / math.sqrt(d) + scores_mask, dim=-1)
        context = (probs @ heads(self._linear(x, v))).transpose(1, 2).reshape(B, L, H)
        attended = self._norm(self._linear(context, o) + x, norm1)
        inner_out = F.gelu(self._linear(attended, inner))
        return self._norm(self._linear(inner_out, outer) + attended, norm2)

    def _position_bias(self, length: int) -> torch.Tensor:
        """(1, heads, L, L) MPNet's learnt bias by bucketed relative position."""
        rel = torch.arange(length)[None, :] - torch.arange(length)[:, None]   # key - query
        buckets = relative_buckets(rel)
        table = self.w["encoder.relative_attention_bias.weight"]             # (32, heads)
        return table[buckets].permute(2, 0, 1)[None]


def relative_buckets(relative: torch.Tensor, n_buckets: int = 32,
                     max_distance: int = 128) -> torch.Tensor:
    """T5's bucket of each relative position (key minus query, any shape, long): half the
    buckets per direction; exact below a quarter of ``n_buckets``, logarithmic beyond, the
    last bucket from ``max_distance`` on."""
    half = n_buckets // 2
    n = -relative
    out = (n < 0).long() * half
    n = n.abs()
    exact = half // 2
    far = exact + (torch.log(n.float().clamp(min=1) / exact) / math.log(max_distance / exact)
                   * (half - exact)).long()
    far = torch.minimum(far, torch.full_like(far, half - 1))
    return out + torch.where(n < exact, n, far)


def _weights(folder: Path) -> dict[str, torch.Tensor]:
    if (folder / "model.safetensors").is_file():
        from safetensors.torch import load_file
        return load_file(str(folder / "model.safetensors"))
    return torch.load(folder / "pytorch_model.bin", map_location="cpu", weights_only=True)

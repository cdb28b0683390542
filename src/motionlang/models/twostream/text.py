"""The two-stream model's token features: the source its config asks for
(``models.text_tokens``, shared with the other families that read pretrained text)."""
from __future__ import annotations

from motionlang.models.text_tokens import CachedTokens, GloveTokens, TransformerTokens


def build_text_encoder(config) -> CachedTokens:
    """The token-feature source a :class:`TwoStreamConfig` asks for."""
    if config.word_vectors:
        return GloveTokens()
    return TransformerTokens(config.text_model, config.text_layers)

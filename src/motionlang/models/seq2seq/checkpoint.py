"""The seq2seq models' extra checkpoint state: vocabulary, normaliser and fitted features."""
from __future__ import annotations

from typing import Any, cast

from motionlang.models.checkpoint import (
    Checkpointed,
    pack_features,
    pack_normalizer,
    pack_vocab,
    unpack_features,
    unpack_normalizer,
    unpack_vocab,
)
from motionlang.models.schema import FEATURES, NORMALIZER, VOCAB


class Seq2SeqCheckpointed(Checkpointed):
    """Checkpoints of models built as ``cls(config, vocab, normalizer, features)`` (M2L and
    L2M): ``"vocab"``, ``"normalizer"`` and ``"features"`` (the fitted ``FeatureSet`` the
    model reads, with its frame rate and layout) beside config and weights."""

    vocab: Any
    normalizer: Any
    features: Any
    state_schema = {"vocab": VOCAB, "normalizer": NORMALIZER, "features": FEATURES}

    def checkpoint_state(self) -> dict[str, Any]:
        return {"vocab": pack_vocab(self.vocab), "normalizer": pack_normalizer(self.normalizer),
                "features": pack_features(self.features)}

    @classmethod
    def from_state(cls, config: Any, state: dict[str, Any]) -> Any:
        return cast(Any, cls)(config, unpack_vocab(state.get("vocab")),
                   unpack_normalizer(state.get("normalizer")),
                   unpack_features(state.get("features")))

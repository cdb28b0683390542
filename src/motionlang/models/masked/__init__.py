"""Masked-token text-to-motion (MoMask-style): a residual-VQ tokenizer over the 21-joint
position features (:mod:`.tokenizer`), a masked bidirectional transformer over the base
tokens with a residual transformer for the finer codebooks and a length estimator
(:mod:`.transformer`), iterative decoding and in-betweening (:mod:`.sampling`), the model
that holds them (:mod:`.model`) and its configuration (:mod:`.config`).

The names below are imported on first use, so that reading the configuration (the command
line's defaults) does not load torch."""
_NAMES = {"MaskedConfig": "config", "MaskedOptions": "config", "MaskedModel": "model"}


def __getattr__(name: str):
    if name in _NAMES:
        import importlib
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_NAMES)

"""The text-motion evaluator of Guo et al. 2022 (the field's yardstick): configuration
(:mod:`.config`), text input and part-of-speech tagger (:mod:`.text`), the public encoders
(:mod:`.layers`) and the model with its loss and checkpoints (:mod:`.model`).

The names below are imported on first use, so that reading the configuration (the command
line's defaults) does not load torch."""
_NAMES = {"EvaluatorConfig": "config", "TextMotionEvaluator": "model", "official_config": "model"}


def __getattr__(name: str):
    if name in _NAMES:
        import importlib
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_NAMES)

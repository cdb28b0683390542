"""Text-motion retrieval (TMR-style): a motion encoder over the 21-joint position features
and a projection of frozen MiniLM sentence vectors, trained contrastively into one space
(:mod:`.model`), its configuration (:mod:`.config`) and sentence vectors (:mod:`.text`).

The names below are imported on first use, so that reading the configuration (the command
line's defaults) does not load torch."""
_NAMES = {"RetrievalConfig": "config", "RetrievalModel": "model",
          "SentenceVectors": "text", "sentence_vectors": "text"}


def __getattr__(name: str):
    if name in _NAMES:
        import importlib
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_NAMES)

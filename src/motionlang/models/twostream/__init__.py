"""Compositional text-to-motion: the hierarchical two-stream model of Ghosh et al. (2021).

The names below are imported on first use, so that reading the family's registry entry or
its configuration does not load torch."""
_NAMES = {"DEFAULT_LAMBDAS": "config", "KIT21_PART_JOINTS": "config",
          "TwoStreamConfig": "config", "kit21_parts": "config", "TwoStreamModel": "model"}


def __getattr__(name: str):
    if name in _NAMES:
        import importlib
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_NAMES)

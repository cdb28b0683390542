"""Rendering: animated stick figures (GIF/MP4), pose strips and trajectory plots (PNG), and
generated results written by their extension (:mod:`.output`).

All figures are drawn with an explicit Agg canvas (no pyplot state) and written atomically.
The names below are imported on first use, so that importing a submodule (or the API) does
not load matplotlib.
"""
_NAMES = {"render_animation": "animation", "animation_frames": "animation",
          "render_strip": "strip", "plot_trajectory": "trajectory", "Scene": "scene",
          "build_scene": "scene", "contact_frames": "scene", "footsteps": "scene"}


def __getattr__(name: str):
    if name in _NAMES:
        import importlib
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_NAMES)

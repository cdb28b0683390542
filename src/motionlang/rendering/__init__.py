"""Rendering: animated stick figures (GIF/MP4), pose strips and trajectory plots (PNG), and
generated results written by their extension (:mod:`.output`).

All figures are drawn with an explicit Agg canvas (no pyplot state) and written atomically."""

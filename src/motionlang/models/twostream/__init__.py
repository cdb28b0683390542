"""Compositional text-to-motion: the hierarchical two-stream model of Ghosh et al. (2021)."""

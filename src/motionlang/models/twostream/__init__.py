"""Compositional text-to-motion: the hierarchical two-stream model of Ghosh et al. (2021)."""
from motionlang.models.twostream.config import (
                                                DEFAULT_LAMBDAS,
                                                KIT21_PART_JOINTS,
                                                TwoStreamConfig,
                                                kit21_parts,
)
from motionlang.models.twostream.model import TwoStreamModel

__all__ = ["DEFAULT_LAMBDAS", "KIT21_PART_JOINTS", "TwoStreamConfig", "TwoStreamModel",
           "kit21_parts"]

"""Feature representations of motions for the models, and the helpers they share.

* :class:`AnglesFeatures` — MMM joint angles + root + active flag, 10 Hz (Plappert 2018).
* :class:`PositionFeatures` — 21 KIT joints in the body frame + root trajectory, 12.5 Hz
  (Ghosh et al. 2021).
* :class:`TaylorFeatures` — root increments + per-bone exp-maps, 30 Hz (Taylor et al. 2006).
* :class:`Normalizer`, padding/masks (:mod:`.collate`), the 21-joint map (:mod:`.joint_map`).
* :func:`~motionlang.datasets.feature_cache.dataset_features` — a dataset fitted and encoded
  once, cached on disk keyed by source files and options.
"""
# importing the feature modules here registers their kinds with base.features_from_dict
# and base.make_features, which rely on it (base cannot import its own subclasses)
from motionlang.features.angles import AnglesConfig, AnglesFeatures
from motionlang.features.base import FeatureSet, downsample, features_from_dict, make_features
from motionlang.features.collate import lengths_to_mask, pad_batch, unpad
from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS, positions21
from motionlang.features.normalizer import Normalizer
from motionlang.features.positions import PositionFeatures, PositionsConfig
from motionlang.features.taylor import TaylorConfig, TaylorFeatures

__all__ = ["AnglesConfig", "AnglesFeatures", "FeatureSet", "KIT21_NAMES", "KIT21_PARENTS",
           "Normalizer", "PositionFeatures", "PositionsConfig", "TaylorConfig",
           "TaylorFeatures", "downsample", "features_from_dict", "lengths_to_mask",
           "make_features",
           "pad_batch", "positions21", "unpad"]

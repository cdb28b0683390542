"""The text-motion evaluator of Guo et al. 2022 (the field's yardstick): configuration
(:mod:`.config`), text input and part-of-speech tagger (:mod:`.text`), the public encoders
(:mod:`.layers`) and the model with its loss and checkpoints (:mod:`.model`)."""
from motionlang.models.evaluator.config import EvaluatorConfig
from motionlang.models.evaluator.model import TextMotionEvaluator, official_config

__all__ = ["EvaluatorConfig", "TextMotionEvaluator", "official_config"]

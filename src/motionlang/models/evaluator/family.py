"""The evaluator's entry in the model registry (the text-motion encoders of Guo et al. 2022)."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="evaluator", model="motionlang.models.evaluator.model:TextMotionEvaluator",
           summary="text-motion evaluator (Guo et al. 2022 protocol)",
           config="motionlang.models.evaluator.config:EvaluatorConfig",
           recipe="motionlang.recipes.evaluator:EVALUATOR"),
)

"""The judge's entry in the model registry (action and style of real motion)."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="judge", model="motionlang.models.judge.model:MotionJudge",
           summary="action and style classifier of real motion",
           config="motionlang.models.judge.config:JudgeConfig",
           recipe="motionlang.recipes.judge:JUDGE"),
)

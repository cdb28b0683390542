"""The retrieval family's entry in the model registry (text-motion retrieval, TMR-style)."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="retrieval", model="motionlang.models.retrieval.model:RetrievalModel",
           summary="text-motion retrieval model: contrastive text and motion encoders into one "
                   "space (TMR-style; frozen MiniLM sentence vectors)",
           config="motionlang.models.retrieval.config:RetrievalConfig",
           recipe="motionlang.recipes.retrieval:RETRIEVAL",
           encodes_text="motionlang.models.retrieval.model:text_vector",
           encodes_motion="motionlang.models.retrieval.model:motion_vector"),
)

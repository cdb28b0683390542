"""The masked-token family's entry in the model registry (MoMask-style text-to-motion)."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="masked", model="motionlang.models.masked.model:MaskedModel",
           summary="English -> motion by masked tokens (MoMask-style: residual-VQ tokenizer, "
                   "masked transformer, frozen MiniLM sentence vectors); text-conditioned "
                   "in-betweening",
           config="motionlang.models.masked.config:MaskedConfig",
           recipe="motionlang.recipes.masked:MASKED",
           text_to_motion="self"),
)

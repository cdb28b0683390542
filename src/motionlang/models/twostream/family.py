"""The two-stream family's entry in the model registry (Ghosh et al. 2021)."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="twostream", model="motionlang.models.twostream.model:TwoStreamModel",
           summary="hierarchical two-stream text-to-motion model (Ghosh et al. 2021)",
           config="motionlang.models.twostream.config:TwoStreamConfig",
           recipe="motionlang.recipes.twostream:TWOSTREAM",
           text_to_motion="motionlang.models.twostream.t2m:TwoStreamText2Motion",
           encodes_text="motionlang.models.twostream.t2m:twostream_text_vector",
           encodes_motion="motionlang.models.twostream.t2m:twostream_motion_vector"),
)

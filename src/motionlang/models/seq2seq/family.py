"""The seq2seq family's entries in the model registry: the M2L and the L2M."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="m2l", model="motionlang.models.seq2seq.m2l:MotionToLanguage",
           summary="motion-to-language model (Plappert et al. 2018)",
           config="motionlang.models.seq2seq.config:M2LConfig",
           recipe="motionlang.recipes.seq2seq:M2L",
           describes="motionlang.models.seq2seq.decode.grounded:describe",
           encodes_motion="motionlang.models.seq2seq.decode.search:embed_motion"),
    Family(kind="l2m", model="motionlang.models.seq2seq.l2m:LanguageToMotion",
           summary="language-to-motion model (Plappert et al. 2018)",
           config="motionlang.models.seq2seq.config:L2MConfig",
           recipe="motionlang.recipes.seq2seq:L2M",
           text_to_motion="motionlang.models.seq2seq.t2m:L2MText2Motion",
           encodes_text="motionlang.models.seq2seq.decode.search:embed_sentence"),
)

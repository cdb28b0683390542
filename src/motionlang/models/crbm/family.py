"""The CRBM family's entries in the model registry (Taylor, Hinton & Roweis 2006): one
level, the two-level stack, and the linear autoregressive baseline (numpy checkpoints)."""
from motionlang.models.family import Family

FAMILIES = (
    Family(kind="crbm", model="motionlang.models.crbm.model:CRBM",
           summary="conditional RBM of motion (Taylor et al. 2006)",
           config="motionlang.models.crbm.config:CRBMConfig", model_file="model.npz",
           recipe="motionlang.recipes.crbm:CRBM"),
    Family(kind="crbm_stack", model="motionlang.models.crbm.stack:CRBMStack",
           summary="two-level CRBM stack (Taylor et al. 2006, sec. 4)", model_file="model.npz"),
    Family(kind="ar", model="motionlang.models.crbm.ar:ARModel",
           summary="linear autoregressive baseline of the CRBM", model_file="model.npz"),
)

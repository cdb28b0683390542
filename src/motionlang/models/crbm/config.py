"""The CRBM's hyper-parameters (:class:`CRBMConfig`) and the names of its parameter arrays."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from motionlang.errors import MotionlangError

#: the parameter arrays of a CRBM: W (D, H), A (n*D, D), B (n*D, H), a (D,), b (H,)
PARAMS = ("W", "A", "B", "a", "b")


@dataclass
class CRBMConfig:
    """Hyper-parameters. Size, order, batch, passes and learning rate are the paper's
    (Taylor et al. 2006: 200 hidden units, order 3, batches of 100, 4000 passes). Weight
    decay is 10x that of Taylor's published code (2e-4). The settings selected for the CMU
    experiment on held-out training trials (``crbm_reproduce.SELECTED``, the CLI's
    defaults) also decay the autoregressive weights more: ``weight_decay_autoregressive``
    2e-2."""
    n_hidden: int = 200
    order: int = 3              # n, frames of past that condition the current frame
    lr: float = 1e-3            # learning rate of W, B and the biases
    lr_autoregressive: float = 1e-3   # learning rate of A
    momentum: float = 0.9
    weight_decay: float = 2e-3  # L2 on W and B (never on biases)
    weight_decay_autoregressive: float | None = None  # L2 on A; None = weight_decay
    batch_size: int = 100
    epochs: int = 4000
    init_std: float = 0.01
    seed: int = 0
    visible: str = "gaussian"   # "gaussian" (unit variance) or "binary"
    dtype: str = "float32"      # of weights and training arithmetic: float32 is 3x faster here
    blas_threads: int | None = 1  # the matrices are small: one BLAS thread avoids oversubscription
    cd_steps: int = 1           # k of CD-k (the paper: 1)
    negative_start: str = "data"  # where the negative chain starts: "data" (v_t, the paper's
    # CD) or "previous" (v_{t-1}, as generation starts each frame: the model learns to move
    # from the last frame to this one; not in the paper)
    history_noise: float = 0.0  # std of Gaussian noise added to the past frames (normalised
    # units) while training, so that generation, which conditions on its own imperfect
    # frames, is trained for inputs off the data (not in the paper; 0 = the paper)

    def __post_init__(self):
        if self.visible not in ("gaussian", "binary"):
            raise MotionlangError(f"CRBMConfig.visible must be 'gaussian' or 'binary', got {self.visible!r}")
        if self.dtype not in ("float32", "float64"):
            raise MotionlangError(f"CRBMConfig.dtype must be 'float32' or 'float64', got {self.dtype!r}")
        if self.negative_start not in ("data", "previous"):
            raise MotionlangError(f"CRBMConfig.negative_start must be 'data' or 'previous', "
                                  f"got {self.negative_start!r}")
        from motionlang.utils.checks import check_numbers
        check_numbers("CRBMConfig", self, positive_ints=("n_hidden", "order", "batch_size",
                                                         "cd_steps"),
                      nonneg_ints=("epochs",), positive=("lr",),
                      nonneg=("lr_autoregressive", "weight_decay", "init_std",
                              "history_noise", "weight_decay_autoregressive"),
                      unit=("momentum",))
        if self.cd_steps < 1:
            raise MotionlangError("CRBMConfig.cd_steps must be >= 1")
        if not (self.history_noise >= 0 and np.isfinite(self.history_noise)):
            raise MotionlangError(f"CRBMConfig.history_noise must be finite and >= 0, got {self.history_noise}")
        if self.order < 1 or self.n_hidden < 1 or self.batch_size < 1:
            raise MotionlangError("CRBMConfig: order, n_hidden and batch_size must be >= 1")


def config_from_dict(d: dict) -> CRBMConfig:
    """CRBMConfig from a checkpoint's dict; keys this version does not know are ignored."""
    known = {f.name for f in dataclasses.fields(CRBMConfig)}
    return CRBMConfig(**{k: v for k, v in d.items() if k in known})


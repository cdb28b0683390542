"""The options of the shared trainer, torch-free: the command line builds its ``train``
options from these defaults, and a bad value fails here, once, before any data is read."""
from __future__ import annotations

from dataclasses import dataclass

from motionlang.errors import MotionlangError
from motionlang.training.schedule import check_schedule
from motionlang.utils.checks import check_numbers

#: optimisers by name (``trainer.OPTIMIZERS`` maps them to the torch classes)
OPTIMIZER_NAMES = ("nadam", "adam", "adamw", "sgd")


@dataclass
class TrainConfig:
    """Options of :class:`~motionlang.training.trainer.Trainer`.

    batch_size is the GLOBAL batch (split across ranks under torchrun). grad_clip is a max
    global L2 norm (None: no clipping). checkpoint_every: also write ``last.pt`` every this
    many steps (0: at epoch ends only). progress: None shows the bar on a terminal only.
    length_buckets: 0 = batches of a plain shuffle; N > 0 = the shuffled order is cut into
    pools of N batches, each pool sorted by sequence length before it is cut into batches,
    and the batches are shuffled again: batches of similar lengths, so that padding (and an
    unrolled decoder's wasted steps) stays small. Still a function of (seed, epoch) only.
    decay_epochs: the last this many epochs lower the learning rate along a half cosine to
    ``lr * decay_to`` (:func:`~motionlang.training.schedule.learning_rate`); 0 keeps it
    constant. The rate is set before every step from ``lr`` and the step's place in the run,
    so ``lr`` and the decay given to a resumed run win over the checkpoint's optimiser state.
    """

    epochs: int = 10
    batch_size: int = 128
    lr: float = 1e-3
    optimizer: str = "nadam"
    weight_decay: float = 0.0
    grad_clip: float | None = None
    seed: int = 0
    out_dir: str = "runs/train"
    checkpoint_every: int = 0
    plot: bool = True
    progress: bool | None = None
    length_buckets: int = 0
    decay_epochs: float = 0.0
    decay_to: float = 0.01

    def __post_init__(self):
        check_numbers("TrainConfig", self, positive_ints=("epochs", "batch_size"),
                      nonneg_ints=("checkpoint_every", "length_buckets"),
                      positive=("lr",), nonneg=("weight_decay", "grad_clip"))
        check_schedule(self.decay_epochs, self.decay_to, self.epochs)
        if self.optimizer not in OPTIMIZER_NAMES:
            raise MotionlangError(f"unknown optimizer {self.optimizer!r}; "
                                  f"choose from {list(OPTIMIZER_NAMES)}")

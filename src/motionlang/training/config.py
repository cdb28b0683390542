"""The options of the shared trainer, torch-free: the command line builds its ``train``
options from these defaults, and a bad value fails here, once, before any data is read."""
from __future__ import annotations

from dataclasses import dataclass, field

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

    epochs: int = field(default=10, metadata={"help": "passes over the training set"})
    batch_size: int = field(default=128, metadata={
        "help": "sequences per optimiser step (all processes together under torchrun)"})
    lr: float = field(default=1e-3, metadata={"help": "learning rate"})
    optimizer: str = "nadam"
    weight_decay: float = field(default=0.0, metadata={
        "help": "the optimiser's weight decay (AdamW: decoupled from the gradient)"})
    grad_clip: float | None = field(default=None, metadata={
        "metavar": "NORM", "help": "clip the gradient's global L2 norm to NORM (none: no "
                                   "clipping)"})
    seed: int = field(default=0, metadata={
        "help": "seed of the split, the initial weights and the batch order"})
    out_dir: str = "runs/train"
    checkpoint_every: int = field(default=0, metadata={
        "metavar": "STEPS", "help": "also write last.pt every STEPS optimiser steps (0: at "
                                    "the end of each epoch only)"})
    plot: bool = True
    progress: bool | None = None
    length_buckets: int = field(default=0, metadata={
        "metavar": "N", "help": "batch sequences of similar lengths (pools of N batches sorted "
                                "by length; 0: plain shuffle): less padding, faster epochs"})
    decay_epochs: float = field(default=0.0, metadata={
        "metavar": "N", "help": "lower the learning rate along a half cosine over the last N "
                                "epochs (also when resuming a run trained at a constant "
                                "rate; 0: constant)"})
    decay_to: float = field(default=0.01, metadata={
        "metavar": "F", "help": "the rate at the last step, as a fraction of --lr"})

    def __post_init__(self):
        check_numbers("TrainConfig", self, positive_ints=("epochs", "batch_size"),
                      nonneg_ints=("checkpoint_every", "length_buckets"),
                      positive=("lr",), nonneg=("weight_decay", "grad_clip"), seeds=("seed",))
        try:
            check_schedule(self.decay_epochs, self.decay_to, self.epochs)
        except MotionlangError as exc:   # named as the other fields are
            raise MotionlangError(f"TrainConfig.{exc}") from None
        if self.optimizer not in OPTIMIZER_NAMES:
            raise MotionlangError(f"unknown optimizer {self.optimizer!r}; "
                                  f"choose from {list(OPTIMIZER_NAMES)}")

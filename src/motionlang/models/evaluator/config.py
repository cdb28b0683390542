"""Configuration of the text-motion evaluator (Guo et al. 2022, "Generating Diverse and
Natural 3D Human Motions from Text"; public code ``EricGuo5513/text-to-motion``).

The sizes of the public evaluator (``networks/evaluator_wrapper.py`` and the
``TrainTexMotMatchOptions`` defaults there): word vectors 300 (GloVe), 15 part-of-speech
classes, text hidden 512, motion hidden 1024, shared embedding 512, movement encoder hidden
and latent 512, movement unit 4 frames, at most 20 words, the 4 foot-contact columns left
out of the motion encoder's input (263 - 4 for HumanML3D, 251 - 4 for KIT-ML).
:meth:`EvaluatorConfig.official` builds that configuration; the defaults here are a smaller
model on GloVe 50d, which is what this package ships word vectors for.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.utils.checks import check_bones, check_numbers

#: the motion feature size of each public dataset (``dataset_name`` "t2m" / "kit")
OFFICIAL_POSE_DIMS = {"humanml3d": 263, "kit": 251}
LOSSES = ("hinge", "infonce")
#: the largest layer size a config may ask for, so that a mistyped size fails at once
#: instead of exhausting memory (the public evaluator's largest is 1024)
SIZES = ("text_hidden", "motion_hidden", "movement_hidden", "movement_latent", "embed_dim")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    """A field that is a ``train evaluator`` option (``cli.config_options``)."""
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class EvaluatorConfig:
    """Sizes and loss of a :class:`~motionlang.models.evaluator.model.TextMotionEvaluator`.

    Attributes:
        motion_dim: F, values per motion frame given to the evaluator (before ``drop_last``).
        drop_last: trailing columns of each frame the encoders do not see (4: the foot
            contacts of the HumanML3D vectors, as the public evaluator; 0 for other features).
        word_dim: word vector size (50: GloVe 6B 50d; the public evaluator: 300).
        n_pos: part-of-speech one-hot size (15 categories, ``text.POS_CATEGORIES``).
        text_hidden, motion_hidden: GRU sizes of the text and motion encoders.
        movement_hidden, movement_latent: the movement encoder's convolution channels.
        embed_dim: size of the shared text/motion embedding.
        unit_length: frames per movement code (two stride-2 convolutions: 4).
        max_words: words kept of a caption (plus the ``sos``/``eos`` marks).
        loss: ``"hinge"`` (the public loss: squared distance of matched pairs plus the squared
            hinge ``max(0, margin - d)^2`` of shifted pairs) or ``"infonce"`` (symmetric
            cross-entropy over ``-distance / temperature`` of all pairs of the batch).
        margin: the hinge's margin (public: 10). temperature: InfoNCE's.
        dropout: of the movement encoder (public: 0.2).
        bones: ``kit`` body only: 20 bone lengths (m, ``joint_map.bone_lengths21`` order)
            every motion is laid on before its rows are made (``features.body21.
            uniform_bones21``), as the public pipeline retargets every motion to one
            subject's bones; ``train evaluator`` sets them to the training motions' median.
            None (evaluators written before the ``bones`` field existed, and official
            weights, whose HumanML3D rows are on one body already): each on its own.
    """

    motion_dim: int = 251
    drop_last: int = 4
    word_dim: int = 50
    n_pos: int = 15
    text_hidden: int = _opt(128, "GRU size of the text encoder")
    motion_hidden: int = _opt(256, "GRU size of the motion encoder")
    movement_hidden: int = _opt(128, "channels of the movement encoder's convolutions")
    movement_latent: int = _opt(128, "size of the movement codes (4 frames each)")
    embed_dim: int = _opt(128, "size of the shared text/motion embedding")
    unit_length: int = 4
    max_words: int = _opt(20, "words kept of a caption")
    loss: str = _opt("hinge", "hinge: the public contrastive loss (matched pairs near, "
                              "shifted pairs beyond --margin); infonce: cross-entropy over "
                              "the batch", choices=LOSSES)
    margin: float = _opt(10.0, "the hinge's margin")
    temperature: float = _opt(0.1, "InfoNCE's temperature")
    dropout: float = _opt(0.2, "dropout of the movement encoder")
    bones: list[float] | None = None

    def __post_init__(self):
        check_numbers("EvaluatorConfig", self,
                      positive_ints=("n_pos", "max_words"), dims=("motion_dim", "word_dim"),
                      sizes=SIZES,
                      nonneg_ints=("drop_last",), positive=("margin", "temperature"),
                      unit=("dropout",))
        if self.unit_length != 4:
            raise MotionlangError("EvaluatorConfig.unit_length must be 4 (two stride-2 "
                                  f"convolutions), got {self.unit_length!r}")
        if self.drop_last >= self.motion_dim:
            raise MotionlangError(f"EvaluatorConfig.drop_last ({self.drop_last}) leaves no "
                                  f"input of motion_dim {self.motion_dim}")
        if self.n_pos != 15:
            raise MotionlangError(f"EvaluatorConfig.n_pos must be 15 (the public POS "
                                  f"categories), got {self.n_pos!r}")
        self.bones = check_bones("EvaluatorConfig", self.bones)
        if self.loss not in LOSSES:
            raise MotionlangError(f"EvaluatorConfig.loss must be one of {LOSSES}, got "
                                  f"{self.loss!r}")

    @property
    def input_dim(self) -> int:
        """Columns the movement encoder sees: ``motion_dim - drop_last``."""
        return self.motion_dim - self.drop_last

    @classmethod
    def official(cls, dataset: str = "humanml3d") -> EvaluatorConfig:
        """The public evaluator's sizes for ``"humanml3d"`` (263 values a frame) or
        ``"kit"`` (251), so that its weights load (``model.load_official``)."""
        if dataset not in OFFICIAL_POSE_DIMS:
            raise MotionlangError(f"unknown official evaluator {dataset!r} (choose from "
                                  f"{', '.join(OFFICIAL_POSE_DIMS)})")
        return cls(motion_dim=OFFICIAL_POSE_DIMS[dataset], drop_last=4, word_dim=300,
                   text_hidden=512, motion_hidden=1024, movement_hidden=512,
                   movement_latent=512, embed_dim=512)

"""Configuration of the motion judge, free of torch (read by ``--help`` without it).

The fields with a ``help`` are the model options of ``motionlang train judge``
(``cli.config_options``); their checks are the config's own.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.features.positions import DEFAULT_FPS
from motionlang.features.positions import DIM as POSITIONS_DIM
from motionlang.utils.checks import check_bones, check_numbers

#: bounds that keep a mistyped size from allocating gigabytes
AT_MOST = {"hidden": 4096, "embed": 4096, "kernel": 4096, "layers": 16, "window": 100_000}


def _opt(default: Any, help_: str) -> Any:
    """A field that is also a ``train judge`` option."""
    return field(default=default, metadata={"help": help_})


@dataclass
class JudgeConfig:
    """Sizes and labels of :class:`~motionlang.models.judge.model.MotionJudge`.

    Attributes:
        contents, styles: the label names, in the order of the two heads' outputs (from the
            training data, never fixed here).
        n_features: per-frame input size F (the 21-joint position features' size).
        fps: frame rate the judge reads (Hz); other rates are resampled to it.
        hidden: channels of the temporal convolutions; embed: size of the penultimate
            features (the ones FID is computed on).
        layers: convolutions (kernel ``kernel``, dilation 1, 2, 4, ...: a receptive field of
            ``1 + (kernel - 1) (2^layers - 1)`` frames, 61 = 4.9 s by default).
        dropout: on the convolutions' outputs and the embedding, in training.
        window: frames of the random crops trained on (whole motions are judged).
        bones: 20 bone lengths (m, ``joint_map.bone_lengths21`` order) every motion is laid
            on before it is read (``features.body21.uniform_bones21``: bone directions
            kept, root path scaled by the legs), so the judge reads the motion and not the
            body (a generated body's hips 2 cm wider than the training actors' otherwise
            read as "run", whatever it does). ``train judge`` sets them to the training
            takes' median; None (``--as-given``, and judges written before the field): as
            given.
    """

    contents: list[str] = field(default_factory=list)
    styles: list[str] = field(default_factory=list)
    n_features: int = POSITIONS_DIM
    fps: float = DEFAULT_FPS
    hidden: int = _opt(128, "channels of the temporal convolutions")
    embed: int = _opt(128, "size of the features FID is computed on")
    layers: int = _opt(4, "dilated convolutions (dilations 1, 2, 4, ...)")
    kernel: int = _opt(5, "convolution kernel")
    dropout: float = _opt(0.2, "dropout")
    window: int = _opt(48, "frames (at the judge's frame rate) of the random crops trained on")
    bones: list[float] | None = None

    def __post_init__(self):
        check_numbers("JudgeConfig", self, unit=("dropout",), positive=("fps",),
                      dims=("n_features",),
                      positive_ints=("hidden", "embed", "layers", "kernel", "window"))
        for name, top in AT_MOST.items():
            if getattr(self, name) > top:
                raise MotionlangError(f"JudgeConfig.{name} must be <= {top}, got "
                                      f"{getattr(self, name)!r}")
        self.bones = check_bones("JudgeConfig", self.bones)
        if not self.contents or not self.styles:
            raise MotionlangError("JudgeConfig needs its content and style label lists")

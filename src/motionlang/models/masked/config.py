"""Configuration and sampling options of the masked-token model, free of torch (read by
``--help`` without it).

The fields with a ``help`` are the model options of ``motionlang train masked``
(``cli.config_options``); their checks are the config's own.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from motionlang.datasets.canonical import check_reading
from motionlang.errors import MotionlangError
from motionlang.features.positions import DEFAULT_FPS
from motionlang.features.positions import DIM as POSITIONS_DIM
from motionlang.utils.checks import MAX_WIDTH, check_numbers

#: frames per token: two stride-2 convolutions (MoMask and T2M-GPT downsample by 4)
DOWN = 4
#: layer widths, bounded by ``utils.checks.MAX_SIZE`` so a mistyped size fails at once
SIZES = ("width", "code_dim", "codes", "hidden", "max_tokens")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    """A field that is also a ``train masked`` option."""
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class MaskedConfig:
    """Sizes and losses of :class:`~motionlang.models.masked.model.MaskedModel`.

    Attributes:
        n_features, fps: per-frame size F and frame rate (Hz) of the position features the
            tokenizer reads (the model's fitted features decide them).
        text_dim, text_model, text_layer: the frozen sentence vectors (as the retrieval
            family's: MiniLM's last hidden state, mean-pooled; 0: read off the encoder).
        width, depth: channels and residual blocks per level of the 1-D convolutional
            tokenizer (time downsampled by :data:`DOWN`).
        code_dim, codes, quantizers: size of a code, codes per codebook, and codebooks of
            the residual quantiser (the first is the base, the rest quantise what is left).
        quantizer_dropout: probability that a training batch uses only the first k
            codebooks (k uniform), so that coarse codes decode to a whole motion alone.
        ema: decay of the codebooks' exponential moving averages.
        commit, velocity: weights of the commitment loss and of the frame-difference
            (velocity) reconstruction loss beside the frame loss.
        path: weight of the global-position loss: the mean distance in metres between
            the joints placed along the root path integrated over the crop from the
            reconstructed rows and from the true ones (``path.global_joints``). The frame
            loss weighs the root's per-frame step like any coordinate; on a travelling
            motion its small errors add up to a body far off its path.
        foot: weight of the foot-velocity loss: the mean error (m/s) of the foot joints'
            ground-plane velocity, placed as for ``path`` (a foot planted in the motion
            should not slide in its reconstruction).
        window: seconds of the random crops the tokenizer is trained on.
        hidden, layers, heads, dropout: the masked transformer's size.
        res_layers: layers of the residual-token transformer (same width).
        cond_drop: probability that the sentence is replaced by the null condition in
            training (classifier-free guidance needs the unconditioned model).
        max_tokens: the longest motion in tokens (the length estimator's classes).
        goal: fraction of the training motions that are a gap to fill, told where the gap
            must arrive (``goal.gap_goal``); above 0 the masked transformer reads goals and
            in-betweening gives them. Off by default: a packaged model fine-tuned with
            goals did not learn to use them (``docs/results/masked.md``). Checkpoints
            written before it read back as 0.
    """

    n_features: int = POSITIONS_DIM
    fps: float = DEFAULT_FPS
    text_dim: int = 0
    text_model: str = "minilm"
    text_layer: int = 6
    width: int = _opt(128, "channels of the convolutional tokenizer")
    depth: int = _opt(2, "residual blocks per level of the tokenizer")
    code_dim: int = _opt(64, "size of a code vector")
    codes: int = _opt(256, "codes per codebook")
    quantizers: int = _opt(4, "codebooks of the residual quantiser (base + finer)")
    quantizer_dropout: float = _opt(0.2, "probability that a batch uses only the first k "
                                         "codebooks")
    ema: float = _opt(0.99, "decay of the EMA codebook updates")
    commit: float = _opt(0.02, "weight of the commitment loss")
    velocity: float = _opt(0.5, "weight of the velocity (frame difference) loss")
    path: float = _opt(1.0, "weight of the global-position loss (metres, along the "
                            "integrated root path)")
    foot: float = _opt(1.0, "weight of the feet's ground-velocity loss (m/s)")
    window: float = _opt(5.12, "seconds of the crops the tokenizer trains on")
    hidden: int = _opt(192, "width of the masked and residual transformers")
    layers: int = _opt(4, "layers of the masked transformer")
    res_layers: int = _opt(2, "layers of the residual-token transformer")
    heads: int = _opt(4, "attention heads (divides --hidden)")
    dropout: float = _opt(0.1, "dropout in the transformers")
    cond_drop: float = _opt(0.1, "probability of training without the sentence (for "
                                 "classifier-free guidance)")
    max_tokens: int = _opt(94, "longest motion in tokens (4 frames each)")
    goal: float = _opt(0.0, "fraction of training motions that are a gap to fill, told "
                            "where it must arrive (experimental, for in-betweening; 0: "
                            "no goals)")

    def __post_init__(self) -> None:
        check_numbers("MaskedConfig", self, positive_ints=("n_features",),
                      nonneg_ints=("text_dim", "text_layer", "depth"), sizes=SIZES,
                      layers=("quantizers", "layers", "res_layers", "heads"),
                      positive=("fps", "window", "commit"),
                      nonneg=("velocity", "path", "foot", "goal"),
                      unit=("quantizer_dropout", "ema", "dropout", "cond_drop"))
        if self.goal > 1:
            raise MotionlangError(f"MaskedConfig.goal must be a fraction in [0, 1], got "
                                  f"{self.goal}")
        if self.hidden % self.heads:
            raise MotionlangError(f"MaskedConfig.heads ({self.heads}) must divide hidden "
                                  f"({self.hidden})")
        if self.codes < 2:
            raise MotionlangError(f"MaskedConfig.codes must be at least 2, got {self.codes}")
        if not isinstance(self.text_model, str) or not self.text_model:
            raise MotionlangError(f"MaskedConfig.text_model must be 'minilm' or a folder, "
                                  f"got {self.text_model!r}")

    @property
    def window_frames(self) -> int:
        """The tokenizer's crop in frames, a whole number of tokens."""
        return max(DOWN, round(self.window * self.fps / DOWN) * DOWN)

    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict
        return asdict(self)


@dataclass
class MaskedOptions:
    """Sampling options (``--model masked:steps=6,guidance=2``).

    Attributes:
        steps: iterations of the masked decoding (MaskGIT/MoMask: about 10; 6 here, chosen
            on the validation takes, where fewer lost nothing down to 6); each fixes the
            most confident tokens and masks the rest again along the cosine schedule.
        guidance: classifier-free guidance scale of the base tokens (1: the conditioned
            model alone; higher follows the sentence more closely, with less variety).
        res_guidance: the same for the residual-token transformer.
        temperature: of the base tokens' softmax (0: the likeliest token, nothing drawn).
        top_k: draw among the k likeliest tokens only (0: all).
        width: motions per sentence, each drawn with its own seed (``generate --all``
            writes each; none is likelier than another).
        drafts: in-betweening draws this many motions in one batch and keeps the one that
            arrives closest to the kept frames after each gap (``inbetween.arrival_miss``);
            more drafts arrive closer and slide less, at about 30 ms each for 10 s
            (``benchmarks/bench_masked_inbetween.py``).
        reading: how a sentence is given to the sentence encoder
            (``datasets.canonical.read_as``): ``verbs``, each action named in other words
            said with its verb ("puts the left hand up" -> "raises the left hand"; the
            sentences as written were as well read, those in other words better); or
            ``written``.
    """

    steps: int = 6
    guidance: float = 2.0
    res_guidance: float = 2.0
    temperature: float = 1.0
    top_k: int = 0
    width: int = 1
    drafts: int = 32
    reading: str = "verbs"

    def __post_init__(self) -> None:
        check_reading(self.reading)
        check_numbers("masked options", self, positive_ints=("steps", "drafts", "width"),
                      nonneg_ints=("top_k",),
                      nonneg=("guidance", "res_guidance", "temperature"))
        for name, most in (("steps", 100), ("drafts", 64), ("width", MAX_WIDTH)):
            if getattr(self, name) > most:
                raise MotionlangError(f"masked options: {name} must be at most {most}, got "
                                      f"{getattr(self, name)}")

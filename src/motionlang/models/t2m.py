"""Every text-to-motion model behind one kind-neutral interface.

:class:`TextToMotion` (a ``typing.Protocol``) is what a caller needs from such a model: its
output frame rate, whether it draws anything (a deterministic model has no likelihood and
no temperature), its sampling options (a small dataclass per family, ``Options``, given on
the command line as ``--model NAME:key=value,...``: ``models.options``), ``sample`` (global
21-joint positions for sentences and lengths), the words it cannot read, and optional
capabilities (:data:`CAPABILITIES`). :func:`text_to_motion` wraps a loaded model
(``models.registry.load_model``) as its family's registry entry says
(``Family.text_to_motion``); no caller asks a model its kind. A new family either
implements the protocol on its model class (entry ``"self"``) or names an adapter.

:class:`Text2MotionAdapter` is the shared base of the two adapters here, the seq2seq L2M
(Plappert et al. 2018) and the two-stream model (Ghosh et al. 2021). The shorthands
:func:`generate_any`, :func:`default_method`, :func:`output_fps` and
:func:`generate_positions21` call through it.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from motionlang.datasets.canonical import check_reading, read_as
from motionlang.datasets.text import tokenize
from motionlang.errors import MotionlangError
from motionlang.features.foot_lock import lock_feet
from motionlang.features.positions import PositionsConfig, join_global, split_global
from motionlang.models.family import load_object
from motionlang.models.options import build_options
from motionlang.models.registry import families, kinds_with
from motionlang.models.word_map import ReadingOptions, WordMapper, WordOptions, WordReading

#: frame rate of the comparison: the positions features' rate
FPS = PositionsConfig.fps

#: optional capabilities: "start_pose" (``hypotheses`` and ``positions21`` take
#: ``first_frame``, a frame of its own features), "positions_start" (:meth:`start_from21`),
#: "reconstruct" (:meth:`reconstruct21`), "hypotheses" (several ranked results per sentence)
CAPABILITIES = ("start_pose", "positions_start", "reconstruct", "hypotheses")


@runtime_checkable
class TextToMotion(Protocol):
    """The kind-neutral text-to-motion contract every caller uses (``generate``, the
    evaluations, ``ml.text_to_motion``); :class:`Text2MotionAdapter` implements it for any
    model that follows :class:`SamplingModel`, or through a family's own adapter.

    Attributes:
        model: the wrapped model (eval mode).
        options: its sampling options (an instance of its family's ``Options``).
        fps: frame rate of ``hypotheses``' results (Hz).
        deterministic: one result per sentence, no likelihood, no temperature.
        capabilities: the subset of :data:`CAPABILITIES` it supports.
    """

    model: Any
    options: Any
    deterministic: bool
    capabilities: frozenset[str]

    @property
    def fps(self) -> float: ...

    def configure(self, options: Any) -> Any:
        """Set (and check) its sampling options from a dict or an ``Options``."""
        ...

    def describe_options(self) -> dict[str, Any]: ...

    def default_method(self) -> str: ...

    def hypotheses(self, sentence: str, *, max_frames: int | None = None,
                   foot_lock: bool = False, **kw: Any) -> list[tuple[Any, float]]:
        """``[(result, score), ...]`` best first (results at :attr:`fps`)."""
        ...

    def positions21(self, sentence: str, n_frames: int, *, foot_lock: bool = False,
                    **kw: Any) -> np.ndarray:
        """Global 21-joint positions (n_frames, 21, 3) metres at 12.5 Hz."""
        ...

    def sample(self, texts: Sequence[str], lengths: Sequence[int | None], *,
               seed: int = 0) -> list[np.ndarray]: ...

    def unknown_words(self, sentence: str) -> list[str]: ...

    def read_words(self, sentence: str) -> Any: ...

    def frames_for(self, sentence: str) -> int | None: ...


@runtime_checkable
class SamplingModel(Protocol):
    """What a family's model implements to generate through :class:`SelfAdapter` (its
    registry entry says ``text_to_motion="self"``): the rest of :class:`TextToMotion`
    (options checked once, foot lock, re-timing to 12.5 Hz, the comparison's anchoring)
    comes from the adapter. ``sample`` returns global 21-joint positions (T, 21, 3) metres at ``fps`` for each
    sentence, ``lengths`` in frames at ``fps`` (None: the length it plans); ``options`` is
    an instance of its ``Options`` dataclass (its sampling options, e.g. top-k, guidance)."""

    kind: str
    Options: type
    deterministic: bool

    @property
    def fps(self) -> float: ...

    def sample(self, texts: Sequence[str], lengths: Sequence[int | None], *, seed: int,
               options: Any) -> list[np.ndarray]: ...

    def frames_for(self, sentence: str) -> int | None: ...

    def unknown_words(self, sentence: str) -> list[str]: ...


@dataclass
class NoOptions:
    """A model that samples one way."""


@dataclass
class ReadOptions:
    """A model that samples one way (the two-stream model: deterministic) and reads its
    sentences with a pretrained encoder (``word_map.ReadingOptions``).

    Attributes:
        reading: how a sentence is given to the encoder (``datasets.canonical.read_as``):
            ``verbs``, each action named in other words said with its verb; or ``written``.
    """

    reading: str = "verbs"

    def __post_init__(self) -> None:
        check_reading(self.reading)


def _check_words(sentence: str) -> None:
    if not tokenize(sentence):
        raise MotionlangError(f"text {sentence!r} has no words to generate a motion from")


class Text2MotionAdapter:
    """The shared base of the adapters that put a model behind :class:`TextToMotion`.

    A subclass sets ``Options`` (its sampling options dataclass), ``capabilities`` and
    ``deterministic``, and implements ``fps``, ``default_method``, ``_hypotheses`` and
    ``_positions21``.
    """

    Options: type = NoOptions
    deterministic = False
    capabilities: frozenset[str] = frozenset()

    def __init__(self, model, options: Any = None):
        self.model = model
        self.options = self.Options()
        self._reranker = None
        self._words: Any = None   # its vocabulary's WordMapper, built on the first unknown word
        if options is not None:
            self.configure(options)

    def configure(self, options: Any) -> Text2MotionAdapter:
        """Set the sampling options: an ``Options`` instance or a dict of values (text
        from ``--model NAME:key=value`` or Python values), checked once here."""
        if not isinstance(options, self.Options):
            where = f"model {getattr(self.model, 'kind', type(self.model).__name__)}"
            options = build_options(self.Options, options, where)
        self.options = options
        self._reranker = None
        return self

    def describe_options(self) -> dict[str, Any]:
        """The options that differ from the defaults (for reports and row names)."""
        default = asdict(self.Options())
        return {k: v for k, v in asdict(self.options).items() if default.get(k) != v}

    # capabilities as flags, for the callers that branch on one
    @property
    def takes_start_pose(self) -> bool:
        return "start_pose" in self.capabilities

    @property
    def autoencodes(self) -> bool:
        return "reconstruct" in self.capabilities

    @property
    def starts_from_positions(self) -> bool:
        return "positions_start" in self.capabilities

    def sample(self, texts: Sequence[str], lengths: Sequence[int | None], *,
               seed: int = 0) -> list[np.ndarray]:
        """:meth:`positions21` of each sentence with its options; a length of None is the
        one the model plans (10 s without a length model); sentence i draws with
        ``seed + i``."""
        out = []
        for i, (text, n) in enumerate(zip(texts, lengths, strict=True)):
            if n is None:   # the model's plan, at its own rate, else 10 s
                planned = self.frames_for(text)
                n = round(planned * FPS / self.fps) if planned else round(10.0 * FPS)
            out.append(self.positions21(text, max(2, n), seed=seed + i))
        return out

    @property
    def fps(self) -> float:
        raise NotImplementedError

    def default_method(self) -> str:
        """How the model decodes unless told: "mean", "sample" or "beam"."""
        raise NotImplementedError

    def frames_for(self, sentence: str) -> int | None:
        """The length (frames at :attr:`fps`) its length model plans, None without one."""
        lm = getattr(self.model, "length_model", None)
        return None if lm is None else self.model.frames_for(self.read_words(sentence).text)

    def read_words(self, sentence: str) -> Any:
        """How the model reads ``sentence`` (``models.word_map.WordReading``; ``.text`` is
        what it decodes): as its ``reading`` option gives it (``ReadingOptions``), and with
        ``map_words`` on (``WordOptions``) unknown words as known."""
        if isinstance(self.options, ReadingOptions) and self.options.reading != "written":
            sentence = read_as(sentence, self.options.reading)
        unknown = self._unknown_words(sentence)
        if not (unknown and isinstance(self.options, WordOptions) and self.options.map_words):
            return WordReading(sentence, (), tuple(unknown))
        self._words = self._words or WordMapper.of_vocabulary(getattr(self.model, "vocab", None))
        return self._words.read(tokenize(sentence), sentence)

    def unknown_words(self, sentence: str) -> list[str]:
        """The words of ``sentence`` the model cannot read, after :meth:`read_words` (each
        becomes one unknown-word token, or is lost), in order of appearance, each once."""
        return list(self.read_words(sentence).unknown)

    def _unknown_words(self, sentence: str) -> list[str]:
        vocab = getattr(self.model, "vocab", None)
        if vocab is None or not hasattr(vocab, "__contains__"):
            return []   # a pretrained text encoder reads any word
        return list(dict.fromkeys(w for w in tokenize(sentence) if w not in vocab))

    def hypotheses(self, sentence: str, *, max_frames: int | None = None,
                   foot_lock: bool = False, **kw) -> list[tuple[Any, float]]:
        """``[(result, score), ...]`` best first; a result is a Motion (joint angles) or
        global positions (T, 21, 3) metres at :attr:`fps`; score NaN when deterministic.
        ``foot_lock``: move the body with its planted feet and hold them in place
        (``features.foot_lock.lock_feet``; position results only: a joint-angle Motion is
        returned as decoded)."""
        hyps = self._hypotheses(self.read_words(sentence).text, max_frames=max_frames, **kw)
        if not foot_lock:
            return hyps
        return [(lock_feet(r, self.fps) if isinstance(r, np.ndarray) else r, s)
                for r, s in hyps]

    def positions21(self, sentence: str, n_frames: int, *, foot_lock: bool = False, **kw
                    ) -> np.ndarray:
        """Global 21-joint positions (n_frames, 21, 3) metres at 12.5 Hz, anchored at the
        origin facing +Z (:func:`generate_positions21`); ``foot_lock`` as for
        :meth:`hypotheses`."""
        p = self._positions21(self.read_words(sentence).text, n_frames, **kw)
        if not foot_lock:
            return p
        return lock_feet(p, FPS)

    def _hypotheses(self, sentence: str, *, max_frames: int | None = None, **kw
                    ) -> list[tuple[Any, float]]:
        raise NotImplementedError

    def _positions21(self, sentence: str, n_frames: int, **kw) -> np.ndarray:
        raise NotImplementedError

    def reconstruct21(self, p21: np.ndarray) -> np.ndarray:
        """A motion (T, 21, 3) decoded back from the model's embedding of it."""
        raise MotionlangError(f"a {self.model.kind} model does not embed motions")

    def start_from21(self, sentence: str, p21: np.ndarray) -> np.ndarray:
        """``len(p21)`` frames for ``sentence`` starting at ``p21``'s first pose."""
        raise MotionlangError(f"a {self.model.kind} model takes no start pose in positions")


def text_to_motion(model, options: Any = None) -> Any:
    """A loaded text-to-motion model (or an already wrapped one) behind
    :class:`TextToMotion`, as its family's registry entry says (``"self"``: the model
    follows :class:`SamplingModel` and :class:`SelfAdapter` wraps it); ``options``: its
    sampling options (an ``Options`` instance or a dict, e.g. ``ModelSpec.options``),
    checked here.

    Raises:
        MotionlangError: a model that does not turn text into motion (an M2L, a CRBM), or
            options it does not take.
    """
    if isinstance(model, TextToMotion):
        return model if options is None else model.configure(options)
    kind = getattr(model, "kind", None)
    fam = families().get(kind) if isinstance(kind, str) else None
    if fam is None or fam.text_to_motion is None:
        raise MotionlangError(f"a {kind or type(model).__name__} model does not generate "
                              f"motion from text (text-to-motion kinds: "
                              f"{', '.join(kinds_with('text_to_motion'))})")
    adapter = SelfAdapter if fam.text_to_motion == "self" else load_object(fam.text_to_motion)
    return adapter(model, options)


class SelfAdapter(Text2MotionAdapter):
    """:class:`TextToMotion` for a model that follows :class:`SamplingModel`."""

    capabilities = frozenset({"hypotheses"})

    def __init__(self, model, options: Any = None):
        self.Options = model.Options   # the family's own options dataclass
        self.deterministic = bool(model.deterministic)
        super().__init__(model, options)

    @property
    def fps(self) -> float:
        return float(self.model.fps)

    def default_method(self) -> str:
        return "mean" if self.deterministic else "sample"

    def frames_for(self, sentence: str) -> int | None:
        return self.model.frames_for(self.read_words(sentence).text)

    def _unknown_words(self, sentence: str) -> list[str]:
        return list(self.model.unknown_words(sentence))

    def _hypotheses(self, sentence: str, *, max_frames: int | None = None, seed: int = 0,
                    method: str | None = None, width: int | None = None, **_: Any) -> list:
        method = method or getattr(self.options, "method", None)
        if method not in (None, self.default_method()):   # not silently another decoding
            raise MotionlangError(f"method {method!r}: a {self.model.kind} model decodes "
                                  f"only by {self.default_method()!r}")
        _check_words(sentence)
        count = int(width or getattr(self.options, "width", None) or 1)
        texts = [sentence] * max(1, count)
        out = self.model.sample(texts, [max_frames] * len(texts), seed=seed,
                                options=self.options)
        return [(np.asarray(p, dtype=np.float64), float("nan")) for p in out]

    def _positions21(self, sentence: str, n_frames: int, *, seed: int = 0, **_: Any
                     ) -> np.ndarray:
        _check_words(sentence)
        own = max(2, int(np.ceil(n_frames * self.fps / FPS)))
        p = np.asarray(self.model.sample([sentence], [own], seed=seed,
                                         options=self.options)[0], dtype=np.float64)
        if abs(self.fps - FPS) > 1e-9:
            t_src = np.arange(len(p)) / self.fps
            p = interp_frames(p, t_src, np.arange(int(np.floor(t_src[-1] * FPS)) + 1) / FPS)
        return fit_length(anchor(p), n_frames)


def default_method(model) -> str:
    """How a text-to-motion model decodes unless told (:meth:`TextToMotion.default_method`)."""
    return text_to_motion(model).default_method()


def output_fps(model) -> float:
    """Frame rate of a text-to-motion model's output (Hz)."""
    return text_to_motion(model).fps


def generate_any(model, sentence: str, *, max_frames: int | None = None, **kw
                 ) -> list[tuple[Any, float]]:
    """:meth:`TextToMotion.hypotheses` of any text-to-motion model. A sentence without a
    word (``""``, ``"!!!"``) is an error, not an unconditioned motion."""
    _check_words(sentence)
    return text_to_motion(model).hypotheses(sentence, max_frames=max_frames, **kw)


def anchor(p21: np.ndarray) -> np.ndarray:
    """Global (T, 21, 3) -> the same motion moved so that frame 0's root is above the
    origin and faces +Z (the start of every generated motion)."""
    local, v, dyaw, _ = split_global(np.asarray(p21, dtype=np.float64))
    return join_global(local, v, dyaw)


def fit_length(p: np.ndarray, n_frames: int) -> np.ndarray:
    """Crop, or pad by holding the last frame, to exactly ``n_frames`` frames."""
    if len(p) >= n_frames:
        return p[:n_frames]
    return np.concatenate([p, np.repeat(p[-1:], n_frames - len(p), axis=0)])


def interp_frames(p: np.ndarray, t_src: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """(T, ...) frames at times ``t_src`` (increasing) -> (len(t_dst), ...) by linear
    interpolation, held constant outside ``t_src``."""
    flat = np.asarray(p, dtype=np.float64).reshape(len(p), -1)
    out = np.stack([np.interp(t_dst, t_src, flat[:, k]) for k in range(flat.shape[1])], 1)
    return out.reshape((len(t_dst),) + np.shape(p)[1:])


def stretch(p: np.ndarray, n_frames: int) -> np.ndarray:
    """(T, ...) frames re-timed to exactly ``n_frames`` frames spanning the same motion
    (first and last frames kept; a single frame is repeated)."""
    if len(p) == 1:
        return np.repeat(np.asarray(p, dtype=np.float64), n_frames, axis=0)
    return interp_frames(p, np.linspace(0.0, 1.0, len(p)), np.linspace(0.0, 1.0, n_frames))


def generate_positions21(model, sentence: str, n_frames: int, **kw) -> np.ndarray:
    """Sentence -> global 21-joint positions (n_frames, 21, 3) metres at 12.5 Hz, anchored
    at the origin facing +Z.

    Two-stream: decoded for exactly ``n_frames``. L2M: ``method`` "mean" (deterministic)
    or "sample" (one ancestral sample drawn with ``seed``), capped at ``n_frames`` model
    frames at its own rate (an L2M with ``progress_input`` is told that length), angles
    features through forward kinematics (``joint_map.positions21``), re-timed to 12.5 Hz,
    then cropped or held at its last frame to ``n_frames`` (an L2M may end earlier);
    ``skeleton``: the body its joint angles drive (default: the training subjects' mean
    build). ``width`` > 1 with "sample": the likeliest of that many samples, or with
    ``reranker`` (an M2L model) the one under which it finds the sentence likeliest
    (``models.seq2seq.decode.rerank``). ``first_frame`` (L2M only): its motion starts with this frame of
    its own features (``models.seq2seq.decode.search.generate_features``); an L2M told its length runs to
    it (its end flag is not read before). ``foot_lock`` (default off: the model's own
    frames): the body moved with its planted feet, held in place (``features.foot_lock``).
    """
    return text_to_motion(model).positions21(sentence, n_frames, **kw)

"""Every text-to-motion model behind one interface: the seq2seq L2M (Plappert et al. 2018)
and the two-stream model (Ghosh et al. 2021).

:class:`TextToMotion` is what a caller needs from such a model: its output frame rate, how
it decodes unless told, whether it draws anything (a deterministic model has no likelihood
and no temperature), whether it takes a start pose, hypotheses for a sentence, and global
21-joint positions at 12.5 Hz for the comparison table. :func:`text_to_motion` wraps a loaded
model (``models.registry.load_model``) in the implementation for its kind; no caller asks a
model its kind. The shorthands :func:`generate_any`, :func:`default_method`,
:func:`output_fps` and :func:`generate_positions21` call through it.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError

#: frame rate of the comparison (the positions features' rate)
FPS = 12.5


def _check_words(sentence: str) -> None:
    from motionlang.datasets.text import tokenize
    if not tokenize(sentence):
        raise MotionlangError(f"text {sentence!r} has no words to generate a motion from")


class TextToMotion:
    """A text-to-motion model seen through the one interface callers use.

    Attributes:
        model: the wrapped model (eval mode).
        fps: frame rate of :meth:`hypotheses`' results (Hz).
        deterministic: one result per sentence, no likelihood, no temperature.
        takes_start_pose: :meth:`hypotheses` accepts ``first_frame``.
    """

    deterministic = False
    takes_start_pose = False
    #: decodes a motion from its own embedding (:meth:`reconstruct21`)
    autoencodes = False
    #: generates from a sentence and a given first pose in positions (:meth:`start_from21`)
    starts_from_positions = False

    def __init__(self, model):
        self.model = model

    @property
    def fps(self) -> float:
        raise NotImplementedError

    def default_method(self) -> str:
        """How the model decodes unless told: "mean", "sample" or "beam"."""
        raise NotImplementedError

    def frames_for(self, sentence: str) -> int | None:
        """The length (frames at :attr:`fps`) its length model plans, None without one."""
        lm = getattr(self.model, "length_model", None)
        return None if lm is None else self.model.frames_for(sentence)

    def unknown_words(self, sentence: str) -> list[str]:
        """The words of ``sentence`` the model cannot read (each becomes one unknown-word
        token, or is lost), in order of appearance, each once."""
        vocab = getattr(self.model, "vocab", None)
        if vocab is None or not hasattr(vocab, "__contains__"):
            return []   # a pretrained text encoder reads any word
        from motionlang.datasets.text import tokenize
        return list(dict.fromkeys(w for w in tokenize(sentence) if w not in vocab))

    def hypotheses(self, sentence: str, *, max_frames: int | None = None,
                   foot_lock: bool = False, **kw) -> list[tuple[Any, float]]:
        """``[(result, score), ...]`` best first; a result is a Motion (joint angles) or
        global positions (T, 21, 3) metres at :attr:`fps`; score NaN when deterministic.
        ``foot_lock``: move the body with its planted feet and hold them in place
        (``features.foot_lock.lock_feet``; position results only: a joint-angle Motion is
        returned as decoded)."""
        hyps = self._hypotheses(sentence, max_frames=max_frames, **kw)
        if not foot_lock:
            return hyps
        from motionlang.features.foot_lock import lock_feet
        return [(lock_feet(r, self.fps) if isinstance(r, np.ndarray) else r, s)
                for r, s in hyps]

    def positions21(self, sentence: str, n_frames: int, *, foot_lock: bool = False, **kw
                    ) -> np.ndarray:
        """Global 21-joint positions (n_frames, 21, 3) metres at 12.5 Hz, anchored at the
        origin facing +Z (:func:`generate_positions21`); ``foot_lock`` as for
        :meth:`hypotheses`."""
        p = self._positions21(sentence, n_frames, **kw)
        if not foot_lock:
            return p
        from motionlang.features.foot_lock import lock_feet
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


class L2MText2Motion(TextToMotion):
    """The seq2seq L2M: decodes by sampling, a sampled beam or component means
    (``decoding.seq2seq.generate``); starts from a given pose if asked."""

    takes_start_pose = True

    @property
    def fps(self) -> float:
        return float(self.model.features.fps)

    def default_method(self) -> str:
        # trained on its own expected frames (rollout_input "mean"): continue them. Joint
        # positions drawn from the mixture get independent noise per coordinate, which
        # stretches bones (the packaged position L2M's sampled waves: forearms of 0.2-2.9 m,
        # 95th-percentile bone-length error 50-170 %; its expected frames: 6-50 %); joint
        # angles sample (a beam keeps the likeliest frames, and standing still is always
        # likelier than moving)
        if getattr(self.model.config, "rollout_input", None) == "mean":
            return "mean"
        kind = getattr(getattr(self.model, "features", None), "kind", None)
        return "mean" if kind == "positions" else "sample"

    def _hypotheses(self, sentence: str, *, max_frames: int | None = None, **kw
                    ) -> list[tuple[Any, float]]:
        from motionlang.decoding.seq2seq import generate
        _check_words(sentence)
        kw.setdefault("method", self.default_method())
        if self.model.config.progress_input:   # told its length: max_frames is the length
            return generate(self.model, sentence, n_frames=max_frames, **kw)
        return generate(self.model, sentence, max_frames=max_frames, **kw)

    @torch.no_grad()
    def _positions21(self, sentence: str, n_frames: int, *, seed: int = 0,
                     method: str = "mean", skeleton=None, width: int = 1, reranker=None,
                     first_frame: np.ndarray | None = None) -> np.ndarray:
        from motionlang.decoding.seq2seq import generate
        from motionlang.features.base import downsample
        from motionlang.features.joint_map import positions21
        fps = self.fps
        cap = max(1, int(np.ceil(n_frames * fps / FPS)))
        # a model told its length runs to it: its end flag fired up to 12 frames early on 345 of
        # the 556 Bandai test sentences, and the last frame held to the length froze runs
        # mid-stride (a one-frame stop from a 27.8 cm move: experiments/root_checks.py)
        least = cap if self.model.config.progress_input else 1
        result, _ = generate(self.model, sentence, width=width, method=method, seed=seed,
                             n_frames=cap, skeleton=skeleton, reranker=reranker,
                             first_frame=first_frame, min_frames=least)[0]
        if isinstance(result, np.ndarray):  # positions features: already (T, 21, 3) at fps
            p = result
            if abs(fps - FPS) > 1e-9:
                t_src = np.arange(len(p)) / fps
                p = interp_frames(p, t_src,
                                  np.arange(int(np.floor(t_src[-1] * FPS)) + 1) / FPS)
        else:
            p = positions21(downsample(result, FPS) if result.n_frames > 1 else result)
        return fit_length(anchor(p), n_frames)


class TwoStreamText2Motion(TextToMotion):
    """The two-stream model: deterministic, 12.5 Hz, the length its length model plans
    (or the one given); its start pose is given to ``model.generate(start=...)``."""

    deterministic = True
    autoencodes = True
    starts_from_positions = True

    @property
    def fps(self) -> float:
        return FPS

    def _features(self, p21: np.ndarray) -> np.ndarray:
        """Global (T, 21, 3) -> the model's normalised (T, 66) positions features."""
        from motionlang.features.positions import split_global
        local, v, dyaw, _ = split_global(np.asarray(p21, dtype=np.float64))
        raw = np.concatenate([local.reshape(len(p21), -1), v, dyaw[:, None]], axis=1)
        return self.model.normalizer.transform(raw)

    @torch.no_grad()
    def reconstruct21(self, p21: np.ndarray) -> np.ndarray:
        return self.model.positions(self.model.reconstruct(self._features(p21)))

    @torch.no_grad()
    def start_from21(self, sentence: str, p21: np.ndarray) -> np.ndarray:
        return self.model.positions(self.model.generate(
            sentence, len(p21), start=self._features(p21)[0]))

    def default_method(self) -> str:
        return "mean"

    def _hypotheses(self, sentence: str, *, max_frames: int | None = None, **kw
                    ) -> list[tuple[Any, float]]:
        _check_words(sentence)
        if kw.get("first_frame") is not None:
            raise MotionlangError("a start pose applies to L2M models")
        n = max_frames or self.model.frames_for(sentence)
        return [(self.model.generate_positions(sentence, n), float("nan"))]

    @torch.no_grad()
    def _positions21(self, sentence: str, n_frames: int, *, first_frame=None, **kw
                     ) -> np.ndarray:
        if first_frame is not None:
            raise MotionlangError("first_frame is for L2M models; a two-stream model takes "
                                  "its start pose in generate(start=...)")
        return self.model.generate_positions(sentence, n_frames)


#: a model's ``kind`` -> its implementation of the interface
IMPLEMENTATIONS: dict[str, type[TextToMotion]] = {
    "l2m": L2MText2Motion,
    "twostream": TwoStreamText2Motion,
}


def text_to_motion(model) -> TextToMotion:
    """A loaded text-to-motion model (or an already wrapped one) behind the interface.

    Raises:
        MotionlangError: a model that does not turn text into motion (an M2L, a CRBM).
    """
    if isinstance(model, TextToMotion):
        return model
    impl = IMPLEMENTATIONS.get(getattr(model, "kind", None))
    if impl is None:
        raise MotionlangError(f"a {getattr(model, 'kind', type(model).__name__)} model does "
                              f"not generate motion from text (text-to-motion kinds: "
                              f"{', '.join(IMPLEMENTATIONS)})")
    return impl(model)


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
    from motionlang.features.positions import join_global, split_global
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
    (``decoding.rerank``). ``first_frame`` (L2M only): its motion starts with this frame of
    its own features (``decoding.seq2seq.generate_features``); an L2M told its length runs to
    it (its end flag is not read before). ``foot_lock`` (default off:
    the model's own frames): the body moved with its planted feet, which are held in place
    (``features.foot_lock``).
    """
    return text_to_motion(model).positions21(sentence, n_frames, **kw)

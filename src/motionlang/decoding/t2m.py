"""Any text-to-motion checkpoint behind one interface: the seq2seq L2M model (Plappert et
al. 2018) and the two-stream model (Ghosh et al. 2021).

* :func:`load_any_t2m` reads a checkpoint (a model file or a trainer's ``best.pt``) and
  builds the model its ``kind`` names.
* :func:`generate_any` has the signature and return value of ``decoding.seq2seq.generate``
  (a list of ``(result, score)``, best first); a two-stream model is deterministic, so it
  returns one hypothesis: global 21-joint positions (T, 21, 3) metres, score NaN, of the
  length its length model predicts for the sentence unless one is given.
* :func:`generate_positions21` gives every model's output as global 21-joint positions at
  12.5 Hz starting at the origin facing +Z — the common ground of the comparison table.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError

#: frame rate of the comparison (the positions features' rate)
FPS = 12.5


def load_any_t2m(path: str | Path, text_encoder=None):
    """A text-to-motion model from its checkpoint, whatever its kind (eval mode).

    Raises:
        MotionlangError: unreadable file, or a kind that is not ``l2m`` / ``twostream``.
    """
    from motionlang.models.checkpoint import load_checkpoint
    d = load_checkpoint(path)
    if isinstance(d, dict) and isinstance(d.get("model"), dict):
        d = d["model"]
    kind = d.get("kind") if isinstance(d, dict) else None
    if kind == "twostream":
        from motionlang.models.twostream import TwoStreamModel
        return TwoStreamModel.from_checkpoint(d, text_encoder)
    if kind == "l2m":
        from motionlang.models.seq2seq.l2m import LanguageToMotion
        return LanguageToMotion.from_checkpoint(d).eval()
    raise MotionlangError(f"{path}: not a text-to-motion checkpoint (kind {kind!r}; "
                          "expected 'l2m' or 'twostream')")


def default_method(model) -> str:
    """How a text-to-motion model decodes unless told: an L2M trained on its own expected
    frames (``rollout_input == "mean"``) or on joint positions with mean decoding, any other
    L2M (joint angles) by ancestral sampling (a beam keeps the likeliest frames, and standing
    still is always likelier than moving); the two-stream model is deterministic ("mean")."""
    if getattr(model, "kind", None) == "twostream":
        return "mean"
    if getattr(model.config, "rollout_input", None) == "mean":
        return "mean"
    # joint positions drawn from the mixture get independent noise per coordinate, which
    # stretches bones (the packaged position L2M's sampled waves: forearms of 0.2-2.9 m,
    # 95th-percentile bone-length error 50-170 %; its expected frames: 6-50 %)
    return "mean" if getattr(getattr(model, "features", None), "kind", None) == "positions" \
        else "sample"


def output_fps(model) -> float:
    """Frame rate of a text-to-motion model's output: the two-stream model's 12.5 Hz, an
    L2M's features' rate."""
    if getattr(model, "kind", None) == "twostream":
        return FPS
    return float(model.features.fps)


def generate_any(model, sentence: str, *, max_frames: int | None = None, **kw
                 ) -> list[tuple[Any, float]]:
    """``decoding.seq2seq.generate`` for L2M (``kw`` passed on); for a two-stream model one
    ``(positions (T, 21, 3), nan)`` with ``T = max_frames`` or ``model.frames_for(sentence)``.
    An L2M told its length (``progress_input``) takes ``max_frames`` as the length too.
    A sentence without a word (``""``, ``"!!!"``) is an error, not an unconditioned motion."""
    from motionlang.datasets.text import tokenize
    if not tokenize(sentence):
        raise MotionlangError(f"text {sentence!r} has no words to generate a motion from")
    if getattr(model, "kind", None) == "twostream":
        return [(model.generate_positions(sentence, max_frames or model.frames_for(sentence)),
                 float("nan"))]
    from motionlang.decoding.seq2seq import generate
    if model.config.progress_input:
        return generate(model, sentence, n_frames=max_frames, **kw)
    return generate(model, sentence, max_frames=max_frames, **kw)


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


@torch.no_grad()
def generate_positions21(model, sentence: str, n_frames: int, *, seed: int = 0,
                         method: str = "mean", skeleton=None, width: int = 1,
                         reranker=None, first_frame: np.ndarray | None = None) -> np.ndarray:
    """Sentence -> global 21-joint positions (n_frames, 21, 3) metres at 12.5 Hz, anchored
    at the origin facing +Z.

    Two-stream: decoded for exactly ``n_frames``. L2M: ``method`` "mean" (deterministic)
    or "sample" (one ancestral sample drawn with ``seed``), capped at ``n_frames`` model
    frames at its own rate (an L2M with ``progress_input`` is told that length), angles
    features through forward kinematics (``joint_map.positions21``), re-timed to 12.5 Hz,
    then cropped or held at its last frame to ``n_frames`` (an L2M may end earlier);
    ``skeleton``: the body
    its joint angles drive (default: the training subjects' mean build). ``width`` > 1
    with "sample": the likeliest of that many samples, or with ``reranker`` (an M2L model)
    the one under which it finds the sentence likeliest (``decoding.rerank``).
    ``first_frame`` (L2M only): its motion starts with this frame of its own features
    (``decoding.seq2seq.generate_features``).
    """
    if getattr(model, "kind", None) == "twostream":
        if first_frame is not None:
            raise MotionlangError("first_frame is for L2M models; a two-stream model takes "
                                  "its start pose in generate(start=...)")
        return model.generate_positions(sentence, n_frames)
    from motionlang.decoding.seq2seq import generate
    from motionlang.features.base import downsample
    from motionlang.features.joint_map import positions21
    fps = float(getattr(getattr(model, "features", None), "fps", FPS))
    cap = max(1, int(np.ceil(n_frames * fps / FPS)))
    result, _ = generate(model, sentence, width=width, method=method, seed=seed,
                         n_frames=cap, skeleton=skeleton, reranker=reranker,
                         first_frame=first_frame)[0]
    if isinstance(result, np.ndarray):  # positions features: already (T, 21, 3) at fps
        p = result
        if abs(fps - FPS) > 1e-9:
            t_src = np.arange(len(p)) / fps
            p = interp_frames(p, t_src, np.arange(int(np.floor(t_src[-1] * FPS)) + 1) / FPS)
    else:
        m = result
        p = positions21(downsample(m, FPS) if m.n_frames > 1 else m)
    return fit_length(anchor(p), n_frames)

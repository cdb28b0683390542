"""The seq2seq L2M (Plappert et al. 2018) behind the text-to-motion interface
(``models.t2m``): its sampling options and its adapter, which its family entry names
(``Family.text_to_motion``)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from motionlang.features.base import downsample
from motionlang.features.joint_map import positions21
from motionlang.models.registry import load_model
from motionlang.models.seq2seq.decode.rerank import check_same_features
from motionlang.models.seq2seq.decode.search import generate
from motionlang.models.t2m import (
    FPS,
    Text2MotionAdapter,
    _check_words,
    anchor,
    fit_length,
    interp_frames,
)
from motionlang.utils.checks import MAX_WIDTH


@dataclass
class L2MOptions:
    """How an L2M samples (``--model l2m:method=sample,width=5``).

    Attributes:
        method: "sample" (ancestral), "beam" (the paper's sampled beam) or "mean" (the
            mixture's expected frames); None: the model's own way for ``generate``, "mean"
            for evaluation rows.
        width: samples (or beam width) per sentence; the likeliest is kept (or, with
            ``rerank``, the one that M2L finds the sentence likeliest for).
        temperature: sharpen the mixture when sampling (1: as trained).
        rerank: an M2L (packaged name, file or run folder) ranking the ``width`` motions.
        length_norm: rank hypotheses by log likelihood per frame.
        map_words: read a word its vocabulary lacks as the nearest known word
            (``models.word_map.WordOptions``; ``generate`` prints what it read as what);
            false: as one unknown-word token.
    """

    method: str | None = field(default=None, metadata={"choices": ("sample", "beam", "mean")})
    width: int = 1
    temperature: float = 1.0
    rerank: str | None = None
    length_norm: bool = False
    map_words: bool = True

    def __post_init__(self) -> None:
        if self.method not in (None, "sample", "beam", "mean"):
            raise ValueError(f"method must be sample, beam or mean, got {self.method!r}")
        if isinstance(self.width, bool) or not 1 <= int(self.width) <= MAX_WIDTH:
            raise ValueError(f"width must be an integer in 1..{MAX_WIDTH}, got {self.width}")
        if not (math.isfinite(self.temperature) and self.temperature > 0):
            raise ValueError(f"temperature must be a finite number > 0, got {self.temperature}")
        if self.method == "mean" and self.width != 1:
            raise ValueError("width applies to 'sample' and 'beam'; mean decoding gives one "
                             "motion")
        if self.method == "mean" and self.temperature != 1.0:
            raise ValueError("temperature applies to 'sample' and 'beam'; mean decoding "
                             "draws nothing")
        if self.rerank and (self.method in (None, "mean") or self.width < 2):
            raise ValueError("rerank ranks several motions: method=sample or beam with "
                             "width 2 or more")


class L2MText2Motion(Text2MotionAdapter):
    """The seq2seq L2M: decodes by sampling, a sampled beam or component means
    (``models.seq2seq.decode.search.generate``); starts from a given pose if asked."""

    Options = L2MOptions
    capabilities = frozenset({"start_pose", "hypotheses"})

    @property
    def reranker(self):
        """The M2L of ``options.rerank``, loaded once and checked against the L2M's
        features; None without one."""
        if self.options.rerank and self._reranker is None:
            self._reranker = load_model(self.options.rerank, kind="m2l")
            check_same_features(self.model, self._reranker, f"rerank={self.options.rerank}")
        return self._reranker

    def _option_kw(self, kw: dict, method_default: str) -> dict:
        o = self.options
        kw.setdefault("method", o.method or method_default)
        if kw["method"] != "mean":
            kw.setdefault("width", o.width)
        if self.reranker is not None:
            kw.setdefault("reranker", self.reranker)
        return kw

    @property
    def fps(self) -> float:
        return float(self.model.features.fps)

    def default_method(self) -> str:
        if self.options.method:   # asked for in its options (``--model l2m:method=sample``)
            return self.options.method
        # trained on its own expected frames (rollout_input "mean"): continue them. Joint
        # positions drawn from the mixture get independent noise per coordinate, which
        # stretches bones far more than the expected frames do (docs/results/real-rigs.md);
        # joint angles sample (a beam keeps the likeliest frames, and standing still is
        # always likelier than moving)
        if getattr(self.model.config, "rollout_input", None) == "mean":
            return "mean"
        kind = getattr(getattr(self.model, "features", None), "kind", None)
        return "mean" if kind == "positions" else "sample"

    def _hypotheses(self, sentence: str, *, max_frames: int | None = None, **kw
                    ) -> list[tuple[Any, float]]:
        _check_words(sentence)
        self._option_kw(kw, self.default_method())
        if self.options.temperature != 1.0:
            kw.setdefault("temperature", self.options.temperature)
        if self.options.length_norm:
            kw.setdefault("length_norm", True)
        if self.model.config.progress_input:   # told its length: max_frames is the length
            return generate(self.model, sentence, n_frames=max_frames, **kw)
        return generate(self.model, sentence, max_frames=max_frames, **kw)

    def positions21(self, sentence: str, n_frames: int, *, foot_lock: bool = False, **kw
                    ) -> np.ndarray:
        return super().positions21(sentence, n_frames, foot_lock=foot_lock,
                                   **self._option_kw(kw, "mean"))

    @torch.no_grad()
    def _positions21(self, sentence: str, n_frames: int, *, seed: int = 0,
                     method: str = "mean", skeleton=None, width: int = 1, reranker=None,
                     first_frame: np.ndarray | None = None, **_) -> np.ndarray:
        fps = self.fps
        cap = max(1, int(np.ceil(n_frames * fps / FPS)))
        # a model told its length runs to it: its end flag fires early on many test
        # sentences, and the last frame held to the length froze runs mid-stride (a one-frame
        # stop; experiments/root_checks.py, figures in docs/results/real-motion.md)
        least = cap if self.model.config.progress_input else 1
        result, _score = generate(self.model, sentence, width=width, method=method,
                                  seed=seed, n_frames=cap, skeleton=skeleton,
                                  reranker=reranker, first_frame=first_frame,
                                  min_frames=least)[0]
        if isinstance(result, np.ndarray):  # positions features: already (T, 21, 3) at fps
            p = result
            if abs(fps - FPS) > 1e-9:
                t_src = np.arange(len(p)) / fps
                p = interp_frames(p, t_src,
                                  np.arange(int(np.floor(t_src[-1] * FPS)) + 1) / FPS)
        else:
            p = positions21(downsample(result, FPS) if result.n_frames > 1 else result)
        return fit_length(anchor(p), n_frames)

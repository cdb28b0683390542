"""The seq2seq L2M (Plappert et al. 2018) behind the text-to-motion interface
(``models.t2m``): its sampling options and its adapter, which its family entry names
(``Family.text_to_motion``)."""
from __future__ import annotations

from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.features.base import downsample
from motionlang.features.joint_map import positions21
from motionlang.models.registry import load_model
from motionlang.models.seq2seq.config import L2MOptions
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

    def configure(self, options: Any) -> L2MText2Motion:
        """The options, checked once; also against this model's own way of decoding (a
        model that decodes by its expected frames draws nothing to sharpen or rank)."""
        super().configure(options)
        o = self.options
        if o.method is None and self.default_method() == "mean":
            # mean decoding gives one motion whatever the width; it draws nothing to
            # sharpen or to rank
            if o.temperature != 1.0:
                raise MotionlangError("temperature applies to 'sample' and 'beam'; mean "
                                      "decoding draws nothing (this model generates with "
                                      "mean decoding, trained on its expected frames; ask "
                                      "for method sample)")
            if o.rerank:
                raise MotionlangError("rerank ranks several motions: this model "
                                      "generates with mean decoding; ask for method sample "
                                      "or beam, width 2 or more")
        return self

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

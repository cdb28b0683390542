"""The two-stream model (Ghosh et al. 2021) behind the text-to-motion interface
(``models.t2m``) and its joint-space encoders; its family entry names them."""
from __future__ import annotations

from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.features.base import downsample
from motionlang.features.body21 import body21
from motionlang.models.t2m import FPS, ReadOptions, Text2MotionAdapter, _check_words


class TwoStreamText2Motion(Text2MotionAdapter):
    """The two-stream model: deterministic, 12.5 Hz, the length its length model plans
    (or the one given); its start pose is given to ``model.generate(start=...)``."""

    deterministic = True
    capabilities = frozenset({"reconstruct", "positions_start"})
    Options = ReadOptions

    @property
    def fps(self) -> float:
        return FPS

    @torch.no_grad()
    def reconstruct21(self, p21: np.ndarray) -> np.ndarray:
        return self.model.positions(self.model.reconstruct(self.model.features_from_positions(p21)))

    @torch.no_grad()
    def start_from21(self, sentence: str, p21: np.ndarray) -> np.ndarray:
        return self.model.positions(self.model.generate(
            sentence, len(p21), start=self.model.features_from_positions(p21)[0]))

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


def twostream_text_vector(model, sentence: str) -> np.ndarray:
    """A sentence -> the two-stream model's joint-space embedding (D,) float32."""
    with torch.no_grad():
        return model.joint(model.encode_text([sentence]))[0].numpy()


def twostream_motion_vector(model, motion) -> np.ndarray:
    """A Motion -> the two-stream model's joint-space pose embedding (D,) float32."""
    p = body21(downsample(motion, FPS) if motion.fps > FPS else motion)
    feats = torch.as_tensor(model.features_from_positions(p),
                            dtype=torch.float32)[None]
    with torch.no_grad():
        return model.joint(model.encode_motion(feats))[0].numpy()

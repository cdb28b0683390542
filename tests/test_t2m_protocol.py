"""A family whose model implements the small SamplingModel protocol (registry entry
``text_to_motion="self"``) gets the whole text-to-motion interface from the generic adapter."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

pytest.importorskip("torch")

from helpers.patching import patch_everywhere
from motionlang.errors import MotionlangError  # noqa: E402
from motionlang.models.t2m import SamplingModel, SelfAdapter, TextToMotion  # noqa: E402


@dataclass
class ToyOptions:
    """A sampled model's options: top-k and a guidance scale."""

    top_k: int = 3
    guidance: float = 2.0

    def __post_init__(self):
        if self.top_k < 1:
            raise ValueError(f"top_k must be >= 1, got {self.top_k}")


class ToyModel:
    """Walks forward along +Z at 1 m/s; ``guidance`` scales its speed (to see options act)."""

    kind = "toy"
    Options = ToyOptions
    deterministic = False
    fps = 25.0

    def __init__(self):
        self.calls: list[tuple] = []

    def sample(self, texts, lengths, *, seed, options):
        self.calls.append((list(texts), list(lengths), seed, options))
        out = []
        for n in lengths:
            n = n or 50
            t = np.arange(n) / self.fps
            p = np.zeros((n, 21, 3))
            p[:, :, 1] = np.linspace(0.0, 1.7, 21)
            p[:, :, 2] = (t * options.guidance / 2.0)[:, None]
            out.append(p)
        return out

    def frames_for(self, sentence):
        return 50

    def unknown_words(self, sentence):
        return [w for w in sentence.split() if w == "zorp"]


def test_the_generic_adapter_gives_the_whole_interface():
    model = ToyModel()
    assert isinstance(model, SamplingModel)
    t2m = SelfAdapter(model, {"top_k": "5"})          # text values, as --model toy:top_k=5
    assert isinstance(t2m, TextToMotion) and t2m.options == ToyOptions(top_k=5)
    p = t2m.positions21("a person walks", 25, seed=4)   # 2 s at 12.5 Hz from 25 Hz frames
    assert p.shape == (25, 21, 3) and np.allclose(p[0, 0, [0, 2]], 0.0)
    assert p[-1, 0, 2] == pytest.approx(24 / 12.5, rel=1e-6)   # 1 m/s, re-timed
    assert model.calls[-1][1] == [50] and model.calls[-1][2] == 4
    hyps = t2m.hypotheses("a person walks", max_frames=30, width=2, foot_lock=True)
    assert len(hyps) == 2 and all(h.shape == (30, 21, 3) for h, _ in hyps)
    assert all(np.isnan(s) for _, s in hyps)
    assert t2m.unknown_words("a zorp walks") == ["zorp"] and t2m.frames_for("x") == 50
    # a planned length: its 50 frames at 25 Hz are 2 s, 25 frames at 12.5 Hz
    assert [len(x) for x in t2m.sample(["a", "b"], [10, None])] == [10, 25]


def test_its_options_are_checked_once_with_a_line_naming_them():
    t2m = SelfAdapter(ToyModel())
    with pytest.raises(MotionlangError, match="unknown option width"):
        t2m.configure({"width": "2"})
    with pytest.raises(MotionlangError, match="top_k must be >= 1"):
        t2m.configure({"top_k": "0"})
    t2m.configure({"guidance": "4"})
    assert t2m.describe_options() == {"guidance": 4.0}
    assert t2m.positions21("a person walks", 13)[-1, 0, 2] == pytest.approx(2.0 * 12 / 12.5)


def test_the_registry_wraps_a_self_family(monkeypatch):
    from motionlang.models import registry
    from motionlang.models.family import Family
    from motionlang.models.t2m import text_to_motion
    fams = {**registry.families(),
            "toy": Family(kind="toy", model="tests:ToyModel", summary="toy",
                          text_to_motion="self")}
    patch_everywhere(monkeypatch, registry, "families", lambda: fams)
    t2m = text_to_motion(ToyModel(), {"top_k": 2})
    assert isinstance(t2m, SelfAdapter) and t2m.options.top_k == 2
    assert text_to_motion(t2m) is t2m

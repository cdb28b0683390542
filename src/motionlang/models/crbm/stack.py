"""Two-level CRBM (Taylor et al. 2006, sec. 3.2): a second CRBM, with binary visibles,
trained greedily on the hidden activations p(h | v_t, past) of the first.

Generation runs both levels: the top model generates the first level's hidden units
(Gibbs sampling with its own past fixed), and the first level turns each generated hidden
vector into visibles through its dynamic visible bias, a* + W h.
"""
from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.models.crbm.checkpoint import arrays, crbm_shapes, open_npz, read_config, read_meta
from motionlang.models.crbm.config import CRBMConfig
from motionlang.models.crbm.model import CRBM
from motionlang.models.crbm.sequences import check_sequences
from motionlang.models.versions import (
    DAMAGE,
    FORMAT_VERSION,
    check_format,
    load_problem,
)
from motionlang.utils.atomic import atomic_path


class CRBMStack:
    """``level1`` (Gaussian visibles, D -> H1) and ``level2`` (binary visibles, H1 -> H2)."""

    def __init__(self, level1: CRBM, level2: CRBM):
        if level2.n_visible != level1.config.n_hidden or level2.config.visible != "binary":
            raise MotionFormatError(None, "level 2 must have binary visibles, one per level-1 hidden unit")
        self.level1, self.level2 = level1, level2

    @classmethod
    def fit(cls, level1: CRBM, sequences: Sequence[np.ndarray], config2: CRBMConfig,
            *, show_progress: bool = False) -> CRBMStack:
        """Train level 2 on a trained ``level1``'s hidden probabilities of ``sequences``."""
        cfg = dataclasses.replace(config2, visible="binary")
        hidden = level1.hidden_activations(sequences)
        level2 = CRBM(cfg, level1.config.n_hidden).fit(hidden, show_progress=show_progress)
        return cls(level1, level2)

    @property
    def n_init(self) -> int:
        """Real frames needed to start generation: level 1's order plus level 2's."""
        return self.level1.config.order + self.level2.config.order

    def generate(self, init: np.ndarray, n_frames: int, *, n_gibbs: int = 30, seed: int = 0,
                 hidden_noise: float = 0.0) -> np.ndarray:
        """``init`` (>= n_init, D) unnormalised -> (len(init) + n_frames, D) unnormalised."""
        l1, l2 = self.level1, self.level2
        n1, n2 = l1.config.order, l2.config.order
        init = check_sequences([init], l1.n_visible, self.n_init, "initial frames")[0]
        rng = np.random.default_rng(seed)
        T0 = len(init)
        v = np.empty((T0 + n_frames, l1.n_visible))
        v[:T0] = l1.normalise(init)
        h = np.empty((T0 + n_frames, l2.n_visible))
        h[:n1] = np.nan   # frames without a full level-1 past have no hidden activation
        for t in range(n1, T0):
            _, b_star = l1.dynamic_biases(v[t - n1:t][::-1].reshape(1, -1))
            h[t] = l1.hidden_probs(v[t:t + 1], b_star)[0]
        for t in range(T0, T0 + n_frames):
            past2 = h[t - n2:t][::-1].reshape(1, -1)
            h[t] = l2.gibbs_frame(h[t - 1:t], past2, rng, n_gibbs, hidden_noise=hidden_noise)[0]
            a_star, _ = l1.dynamic_biases(v[t - n1:t][::-1].reshape(1, -1))
            v[t] = l1.visible_mean(h[t:t + 1], a_star)[0]
        out = l1.denormalise(v)
        out[:T0] = init
        return out

    def save(self, folder_or_path: str | Path) -> None:
        """Both levels in one .npz (keys prefixed ``l1_`` / ``l2_``)."""
        path = Path(folder_or_path)
        with atomic_path(path.with_suffix(".npz"), suffix=".npz") as tmp1:
            parts = {}
            for name, m in (("l1", self.level1), ("l2", self.level2)):
                for k in ("W", "A", "B", "a", "b", "mean", "std"):
                    parts[f"{name}_{k}"] = getattr(m, k)
                parts[f"{name}_meta"] = np.array(json.dumps(
                    {"config": dataclasses.asdict(m.config), "n_visible": m.n_visible}))
            np.savez(tmp1, kind=np.array("crbm_stack"), format=np.array(FORMAT_VERSION), **parts)

    @classmethod
    def load(cls, path: str | Path) -> CRBMStack:
        try:
            with open_npz(path) as z:
                if str(z["kind"]) != "crbm_stack":
                    raise MotionFormatError(path, "not a two-level CRBM checkpoint")
                check_format(path, int(z["format"]) if "format" in z.files else 0)
                levels = []
                for name in ("l1", "l2"):
                    meta = read_meta(path, z, f"{name}_meta", "crbm_stack")
                    config, n_visible = read_config(path, meta, "crbm_stack", CRBMConfig)
                    stored = arrays(path, z, "crbm_stack", crbm_shapes(config, n_visible),
                                    prefix=f"{name}_")
                    m = CRBM(config, n_visible)
                    for k in ("W", "A", "B", "a", "b"):
                        setattr(m, k, stored[k].astype(m.config.dtype))
                    for k in ("mean", "std"):
                        setattr(m, k, stored[k].astype(np.float64))
                    levels.append(m)
        except (OSError, *DAMAGE) as exc:
            raise MotionFormatError(path, load_problem("crbm_stack", exc)) from exc
        return cls(*levels)

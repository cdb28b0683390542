"""Checks of generated motion on CMU subject 35: style per frame, range, style switches.

Style of a generated frame = the label (walk / jog) of the nearest training frame in the
model's normalised feature space (Euclidean over all features except the root's ground
step, whose speed alone would give the style away: the label should judge the pose).

What keeps a generated walk walking is ``CRBMConfig.history_noise``: generation conditions
on its own imperfect frames, and without noise on the past frames while training the walk
drifts into a jog, and the settings that kept walking without it walked on the spot. From the first frames
of some *training* walks the selected model still turns to jogging. The figures, and what
else was tried without a fix, are in ``docs/results/crbm.md`` (Generation).
"""
from __future__ import annotations

import numpy as np

from motionlang.datasets.cmu35 import Cmu35, model_frames
from motionlang.models.crbm.model import CRBM

STYLE_DIMS = np.r_[1, 3:59]   # all model features but the root's ground step
METRES_PER_UNIT = 0.0254 / 0.45   # 35.asf: ":units length 0.45" of inches
FPS = 30.0


def forward_speed(frames: np.ndarray) -> float:
    """Mean forward speed (m/s) of (T, 59) model features: the root's ground-plane step
    along the facing direction (dim 2, see ``datasets.cmu35.model_frames``). Walking on the
    spot ~ 0, backwards < 0."""
    f = np.asarray(frames, dtype=np.float64)
    return float(f[:, 2].mean() * METRES_PER_UNIT * FPS)


class StyleLabeller:
    """Nearest-neighbour walk/jog labels from the training frames (N, 59) model features."""

    def __init__(self, data: Cmu35, mean: np.ndarray, std: np.ndarray):
        frames, labels = [], []
        for ch, name in zip(data.train, data.train_names):
            frames.append(model_frames(ch))
            labels += [data.labels[name]] * len(ch)
        self.mean, self.std = mean, std
        self.train = self._norm(np.concatenate(frames))
        self.labels = np.array(labels)
        raw = np.concatenate(frames)
        self.lo, self.hi, self.sd = raw.min(0), raw.max(0), raw.std(0)

    def _norm(self, x: np.ndarray) -> np.ndarray:
        return ((x - self.mean) / self.std)[:, STYLE_DIMS]

    def __call__(self, frames: np.ndarray) -> np.ndarray:
        """(T, 59) model features -> (T,) 'walk' / 'jog'."""
        a, b = self._norm(frames), self.train
        d2 = (a ** 2).sum(1)[:, None] - 2 * a @ b.T + (b ** 2).sum(1)[None]
        return self.labels[d2.argmin(axis=1)]

    def range_excess(self, frames: np.ndarray) -> float:
        """Largest distance outside the training [min, max], in training std units (0 = inside)."""
        below = (self.lo - frames) / np.where(self.sd > 0, self.sd, 1)
        above = (frames - self.hi) / np.where(self.sd > 0, self.sd, 1)
        return float(max(0.0, below.max(), above.max()))


def _training_speed(data: Cmu35, style: str) -> float:
    """Mean forward speed (m/s) of the training trials of one style (walks ~1.2, jogs ~3.4)."""
    return float(np.mean([forward_speed(model_frames(c)) for c, n in zip(data.train, data.train_names)
                          if data.labels[n] == style]))


def generation_report(model, data: Cmu35, *, n_frames: int = 1000, seed: int = 0,
                      n_gibbs: int = 30, hidden_noise: float = 0.0, n_samples: int = 1,
                      start: int = 0) -> dict:
    """Generate ``n_samples`` sequences of ``n_frames`` from walking (35_29) and jogging (35_18)
    test frames; per start style: fraction of frames keeping the style, range excess, the
    fraction of sequences that switch style (majority of their last 100 frames differs), and
    the mean forward speed (m/s) over the second half of the generated frames next to that
    of the training trials of the style.

    ``model`` is a :class:`CRBM`, a ``CRBMStack`` or an ``ARModel`` (anything with
    ``generate(init, n_frames, seed=...)`` and the normaliser of level 1 as ``mean/std``).
    """
    base = getattr(model, "level1", model)
    lab = StyleLabeller(data, base.mean, base.std)
    n_init = getattr(model, "n_init", base.config.order)
    out = {}
    for style, trial in (("walk", "35_29"), ("jog", "35_18")):
        init = model_frames(data.test[trial])[start:start + n_init]
        keep, excess, speed, switched = [], [], [], 0
        for s in range(n_samples):
            kwargs = {"seed": seed + s}
            if isinstance(model, CRBM) or hasattr(model, "level1"):
                kwargs.update(n_gibbs=n_gibbs, hidden_noise=hidden_noise)
            gen = model.generate(init, n_frames, **kwargs)
            gen = gen[0] if gen.ndim == 3 else gen
            labels = lab(gen[n_init:])
            keep.append(float((labels == style).mean()))
            excess.append(lab.range_excess(gen[n_init:]))
            speed.append(forward_speed(gen[n_init:][-n_frames // 2:]))
            tail = labels[-100:]
            switched += int((tail == style).mean() < 0.5)
        out[style] = {"style_kept": float(np.mean(keep)), "style_kept_min": float(np.min(keep)),
                      "range_excess_std": float(np.max(excess)),
                      "switch_rate": switched / n_samples, "n_samples": n_samples,
                      # m/s over the second half of the generated frames (walking on the spot ~ 0)
                      "forward_speed_last_half": float(np.mean(speed)),
                      "forward_speed_training": _training_speed(data, style)}
    return out


#: the test trial each start style begins from
START_TRIALS = {"walk": "35_29", "jog": "35_18"}


def generate_from_test(model, data: Cmu35, start: str = "walk", n_frames: int = 1000, *,
                       n_gibbs: int = 30, seed: int = 0, hidden_noise: float = 0.0
                       ) -> tuple[np.ndarray, dict]:
    """Generate ``n_frames`` on-line from the first frames of the walking or jogging
    (``start``) test trial with a CRBM or a ``CRBMStack``.

    Returns (frames, report): frames (n_init + n_frames, 59) model features, the real
    starting frames first; report: the fractions of generated frames labelled walk and jog,
    the label changes, the range excess (training std units) and the forward speed (m/s) over
    the last half.
    """
    base = getattr(model, "level1", model)   # a two-level model generates through both
    n = getattr(model, "n_init", base.config.order)
    init = model_frames(data.test[START_TRIALS[start]])[:n]
    gen = model.generate(init, n_frames, n_gibbs=n_gibbs, seed=seed, hidden_noise=hidden_noise)
    gen = gen[0] if gen.ndim == 3 else gen
    lab = StyleLabeller(data, base.mean, base.std)
    labels = lab(gen[n:])
    report = {"frames": n_frames, "start_style": start,
              "fraction_walk": float((labels == "walk").mean()),
              "fraction_jog": float((labels == "jog").mean()),
              "label_changes": int((labels[1:] != labels[:-1]).sum()),
              "range_excess_std": lab.range_excess(gen[n:]),
              "forward_speed_last_half_m_s": forward_speed(gen[n:][-n_frames // 2:])}
    return gen, report

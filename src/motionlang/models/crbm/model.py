"""Conditional restricted Boltzmann machine (Taylor, Hinton & Roweis 2006).

Visible units ``v_t`` (D,) are real valued with unit variance (the model normalises its
input to zero mean, unit standard deviation per dimension) or binary (for a second level
trained on the first one's hidden activations); hidden units ``h_t`` (H,) are binary.
The past ``n`` frames ``p_t = [v_{t-1}, ..., v_{t-n}]`` (n*D,) act as dynamic biases:

    a*_t = a + p_t @ A        (visible,  A: (n*D, D))
    b*_t = b + p_t @ B        (hidden,   B: (n*D, H))
    F(v | p) = 0.5 |v - a*|^2 - sum_j softplus(b*_j + v @ W_j)     (Gaussian visibles)
    F(v | p) = -v @ a*         - sum_j softplus(b*_j + v @ W_j)     (binary visibles)

Training is CD-1 with the paper's approximations: the hidden states are sampled (binary)
for the positive statistics and for the reconstruction, the reconstruction is the visible
mean (no visible noise), and the negative statistics use hidden probabilities.

All public methods take and return *unnormalised* features; the mean and standard
deviation learnt by :meth:`CRBM.fit` are part of the checkpoint.
"""
from __future__ import annotations

import contextlib
import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from motionlang.errors import MotionFormatError, MotionlangError
from motionlang.utils.atomic import atomic_write
from motionlang.utils.progress import progress

PARAMS = ("W", "A", "B", "a", "b")


@dataclass
class CRBMConfig:
    """Hyper-parameters. Size, order, batch, passes and learning rate are the paper's
    (Taylor et al. 2006: 200 hidden units, order 3, batches of 100, 4000 passes). Weight
    decay is 10x that of Taylor's published code (2e-4). The settings selected for the CMU
    experiment on held-out training trials (``crbm_reproduce.SELECTED``, the CLI's
    defaults) also decay the autoregressive weights more: ``weight_decay_autoregressive``
    2e-2."""
    n_hidden: int = 200
    order: int = 3              # n, frames of past that condition the current frame
    lr: float = 1e-3            # learning rate of W, B and the biases
    lr_autoregressive: float = 1e-3   # learning rate of A
    momentum: float = 0.9
    weight_decay: float = 2e-3  # L2 on W and B (never on biases)
    weight_decay_autoregressive: float | None = None  # L2 on A; None = weight_decay
    batch_size: int = 100
    epochs: int = 4000
    init_std: float = 0.01
    seed: int = 0
    visible: str = "gaussian"   # "gaussian" (unit variance) or "binary"
    dtype: str = "float32"      # of weights and training arithmetic: float32 is 3x faster here
    blas_threads: int | None = 1  # the matrices are small: one BLAS thread avoids oversubscription
    cd_steps: int = 1           # k of CD-k (the paper: 1)
    negative_start: str = "data"  # where the negative chain starts: "data" (v_t, the paper's
    # CD) or "previous" (v_{t-1}, as generation starts each frame: the model learns to move
    # from the last frame to this one; not in the paper)
    history_noise: float = 0.0  # std of Gaussian noise added to the past frames (normalised
    # units) while training, so that generation, which conditions on its own imperfect
    # frames, is trained for inputs off the data (not in the paper; 0 = the paper)

    def __post_init__(self):
        if self.visible not in ("gaussian", "binary"):
            raise MotionlangError(f"CRBMConfig.visible must be 'gaussian' or 'binary', got {self.visible!r}")
        if self.dtype not in ("float32", "float64"):
            raise MotionlangError(f"CRBMConfig.dtype must be 'float32' or 'float64', got {self.dtype!r}")
        if self.negative_start not in ("data", "previous"):
            raise MotionlangError(f"CRBMConfig.negative_start must be 'data' or 'previous', "
                                  f"got {self.negative_start!r}")
        from motionlang.utils.checks import check_numbers
        check_numbers("CRBMConfig", self, positive_ints=("n_hidden", "order", "batch_size",
                                                         "cd_steps"),
                      nonneg_ints=("epochs",), positive=("lr",),
                      nonneg=("lr_autoregressive", "weight_decay", "init_std",
                              "history_noise", "weight_decay_autoregressive"),
                      unit=("momentum",))
        if self.cd_steps < 1:
            raise MotionlangError("CRBMConfig.cd_steps must be >= 1")
        if not (self.history_noise >= 0 and np.isfinite(self.history_noise)):
            raise MotionlangError(f"CRBMConfig.history_noise must be finite and >= 0, got {self.history_noise}")
        if self.order < 1 or self.n_hidden < 1 or self.batch_size < 1:
            raise MotionlangError("CRBMConfig: order, n_hidden and batch_size must be >= 1")


def config_from_dict(d: dict) -> CRBMConfig:
    """CRBMConfig from a checkpoint's dict; keys this version does not know are ignored."""
    known = {f.name for f in dataclasses.fields(CRBMConfig)}
    return CRBMConfig(**{k: v for k, v in d.items() if k in known})


def _blas_threads(n: int | None):
    """Limit BLAS threads while training (threadpoolctl, if installed; else no-op)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return contextlib.nullcontext()
    return threadpool_limits(limits=n, user_api="blas") if n else contextlib.nullcontext()


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * x))  # overflow-free logistic


def check_sequences(sequences: Sequence[np.ndarray], dim: int | None, min_frames: int,
                    what: str = "sequence") -> list[np.ndarray]:
    """Validate a list of (T_i, D) arrays: 2-D, same D (= ``dim`` if given), finite,
    T_i >= ``min_frames`` (an order-n model needs n + 1 to learn from, n to start from).

    Raises :class:`MotionFormatError` naming the sequence and frame of the first problem.
    """
    out = []
    if len(sequences) == 0:
        raise MotionFormatError(None, f"no {what}s given")
    for i, s in enumerate(sequences):
        s = np.asarray(s, dtype=np.float64)
        name = f"<{what} {i}>"
        if s.ndim != 2:
            raise MotionFormatError(name, f"expected a (frames, dims) array, got shape {s.shape}")
        if dim is not None and s.shape[1] != dim:
            raise MotionFormatError(name, f"expected {dim} dimensions per frame, got {s.shape[1]}")
        if s.shape[0] < min_frames:
            raise MotionFormatError(name, f"{s.shape[0]} frames: at least {min_frames} needed "
                                    f"(the model's order of past frames, plus the frame itself)")
        bad = ~np.isfinite(s)
        if bad.any():
            f, d = np.argwhere(bad)[0]
            raise MotionFormatError(name, f"non-finite value in dimension {d}", frame=int(f))
        dim = s.shape[1]
        out.append(s)
    return out


def chunk_index(lengths: Sequence[int], order: int) -> np.ndarray:
    """Rows (into the concatenation of sequences of ``lengths``) that have ``order`` past
    frames inside the same sequence; a minibatch is a set of these, never a copied chunk."""
    starts = np.cumsum([0] + list(lengths[:-1]))
    return np.concatenate([np.arange(s + order, s + n) for s, n in zip(starts, lengths)])


def gather_past(frames: np.ndarray, rows: np.ndarray, order: int) -> np.ndarray:
    """(len(rows), order*D): ``[v_{t-1}, ..., v_{t-order}]`` for each row t of ``frames`` (N, D)."""
    return np.concatenate([frames[rows - k] for k in range(1, order + 1)], axis=1)


class CRBM:
    """A trained or trainable CRBM. Parameters: W (D,H), A (nD,D), B (nD,H), a (D,), b (H,)."""

    def __init__(self, config: CRBMConfig, n_visible: int):
        self.config = config
        self.n_visible = int(n_visible)
        rng = np.random.default_rng(config.seed)
        D, H, nD = self.n_visible, config.n_hidden, self.n_visible * config.order
        s = config.init_std
        dt = np.dtype(config.dtype)
        self.W = (s * rng.standard_normal((D, H))).astype(dt)
        self.A = (s * rng.standard_normal((nD, D))).astype(dt)
        self.B = (s * rng.standard_normal((nD, H))).astype(dt)
        self.a = np.zeros(D, dtype=dt)
        self.b = np.zeros(H, dtype=dt)
        self.mean = np.zeros(D)   # normaliser, set by fit()
        self.std = np.ones(D)
        self.history: list[float] = []   # mean squared reconstruction error per epoch

    # ----------------------------------------------------------------- conditionals
    def dynamic_biases(self, past: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """past (N, n*D) normalised -> (a* (N, D), b* (N, H))."""
        return self.a + past @ self.A, self.b + past @ self.B

    def hidden_probs(self, v: np.ndarray, b_star: np.ndarray) -> np.ndarray:
        """p(h=1 | v, past): (N, H)."""
        return _sigmoid(b_star + v @ self.W)

    def visible_mean(self, h: np.ndarray, a_star: np.ndarray) -> np.ndarray:
        """E[v | h, past]: (N, D); Gaussian mean or Bernoulli probability."""
        x = a_star + h @ self.W.T
        return x if self.config.visible == "gaussian" else _sigmoid(x)

    def free_energy(self, v: np.ndarray, past: np.ndarray) -> np.ndarray:
        """F(v | past) per row, (N,); p(v | past) is proportional to exp(-F)."""
        a_star, b_star = self.dynamic_biases(past)
        x = b_star + v @ self.W
        soft = np.logaddexp(0.0, x).sum(axis=1)
        if self.config.visible == "gaussian":
            return 0.5 * ((v - a_star) ** 2).sum(axis=1) - soft
        return -(v * a_star).sum(axis=1) - soft

    # ----------------------------------------------------------------- learning
    def cd_gradients(self, v0: np.ndarray, past: np.ndarray, rng: np.random.Generator | None
                     ) -> tuple[dict[str, np.ndarray], float]:
        """CD-k ascent direction, averaged over the N rows, for normalised ``v0`` (N, D)
        (k = ``config.cd_steps``; the negative chain starts at ``v0`` or, with
        ``negative_start="previous"``, at the past's latest frame).

        With ``rng`` the hidden states are sampled (the paper's rule); with ``rng=None``
        probabilities are used throughout, which makes the result a deterministic function:
        exactly ``-(d/dθ) mean[F(v0|p) - F(v1|p)]`` with the reconstruction v1 held fixed.
        Returns (gradients by parameter name, mean squared reconstruction error).
        """
        N, D = v0.shape
        cfg = self.config
        a_star, b_star = self.dynamic_biases(past)
        ph0 = self.hidden_probs(v0, b_star)

        def sample(p):
            return (p > rng.random(p.shape)).astype(v0.dtype) if rng is not None else p
        h0 = sample(ph0)
        if cfg.negative_start == "previous":   # past[:, :D] is frame t-1
            v1 = past[:, :D]
            h = sample(self.hidden_probs(v1, b_star))
        else:
            h = h0
        for k in range(cfg.cd_steps):
            v1 = self.visible_mean(h, a_star)
            ph1 = self.hidden_probs(v1, b_star)
            if k < cfg.cd_steps - 1:
                h = sample(ph1)
        dh = h0 - ph1                              # hidden-bias statistic, (N, H)
        dv = v0 - v1                               # visible-bias statistic, (N, D)
        grads = {
            "W": (v0.T @ h0 - v1.T @ ph1) / N,
            "a": dv.mean(axis=0),
            "b": dh.mean(axis=0),
            "A": past.T @ dv / N,
            "B": past.T @ dh / N,
        }
        return grads, float((dv ** 2).mean())

    def fit(self, sequences: Sequence[np.ndarray], *, show_progress: bool = False,
            epochs: int | None = None, on_epoch=None) -> "CRBM":
        """Train on a list of (T_i, D) unnormalised sequences (T_i > order each).

        The normaliser is fitted here for Gaussian visibles (binary ones are used as is).
        ``on_epoch(epoch, model)`` (1-based epoch), if given, is called after every pass:
        it lets hyper-parameter selection score snapshots of one run at several epoch counts.
        """
        cfg = self.config
        seqs = check_sequences(sequences, self.n_visible, cfg.order + 1)
        frames = np.concatenate(seqs)
        if cfg.visible == "gaussian":
            self.mean = frames.mean(axis=0)
            sd = frames.std(axis=0)
            self.std = np.where(sd > 1e-8, sd, 1.0)
        x = self.normalise(frames).astype(self.config.dtype)
        rows = chunk_index([len(s) for s in seqs], cfg.order)
        rng = np.random.default_rng(cfg.seed + 1)
        velocity = {k: np.zeros_like(getattr(self, k)) for k in PARAMS}
        rates = {"W": cfg.lr, "B": cfg.lr, "a": cfg.lr, "b": cfg.lr, "A": cfg.lr_autoregressive}
        n_epochs = cfg.epochs if epochs is None else epochs
        epoch_iter = range(n_epochs)
        if show_progress:
            epoch_iter = progress(epoch_iter, desc="crbm", total=n_epochs)
        with _blas_threads(cfg.blas_threads):
            self._epochs(epoch_iter, x, rows, rng, velocity, rates, on_epoch)
        return self

    def _epochs(self, epoch_iter, x, rows, rng, velocity, rates, on_epoch=None) -> None:
        cfg = self.config
        wd_a = cfg.weight_decay if cfg.weight_decay_autoregressive is None else cfg.weight_decay_autoregressive
        decay = {"W": cfg.weight_decay, "B": cfg.weight_decay, "A": wd_a}
        for _ in epoch_iter:
            order = rng.permutation(rows)
            err = 0.0
            for start in range(0, len(order), cfg.batch_size):
                batch = order[start:start + cfg.batch_size]
                past = gather_past(x, batch, cfg.order)
                if cfg.history_noise > 0:
                    past = past + (cfg.history_noise
                                   * rng.standard_normal(past.shape)).astype(past.dtype)
                grads, e = self.cd_gradients(x[batch], past, rng)
                err += e * len(batch)
                for k in PARAMS:
                    g = grads[k]
                    if k in decay:
                        g = g - decay[k] * getattr(self, k)
                    velocity[k] *= cfg.momentum
                    velocity[k] += rates[k] * g
                    getattr(self, k).__iadd__(velocity[k])
            self.history.append(err / len(order))
            if not (np.isfinite(err) and all(np.isfinite(getattr(self, k)).all()
                                             for k in PARAMS)):
                raise MotionlangError(f"training stopped at epoch {len(self.history)}: the "
                                      "reconstruction error or weights are not finite (lower "
                                      "--lr)")
            if on_epoch is not None:
                on_epoch(len(self.history), self)

    # ----------------------------------------------------------------- inference
    def gibbs_frame(self, v: np.ndarray, past: np.ndarray, rng: np.random.Generator,
                    n_gibbs: int = 30, missing: np.ndarray | None = None,
                    hidden_noise: float = 0.0, mean_field: bool = False) -> np.ndarray:
        """Alternating Gibbs updates of one frame with its past fixed (all normalised).

        v (S, D) is the starting point (also the clamped values where ``missing`` (D,) or
        (S, D) is False); past (S, n*D). Hidden states are sampled except in the last
        update, where their probabilities give the mean-field visible (less jitter).
        ``hidden_noise`` is the std of Gaussian noise added to the hidden biases (one draw
        per frame), the paper's way of moving between styles. ``mean_field`` uses hidden
        probabilities in every update (deterministic). Returns the new v (S, D).
        """
        a_star, b_star = self.dynamic_biases(past)
        if hidden_noise > 0:
            b_star = b_star + hidden_noise * rng.standard_normal(b_star.shape)
        v = v.copy()
        for k in range(max(1, n_gibbs)):
            ph = self.hidden_probs(v, b_star)
            h = ph if (mean_field or k == n_gibbs - 1) else (ph > rng.random(ph.shape)).astype(v.dtype)
            mean = self.visible_mean(h, a_star)
            if missing is None:
                v = mean
            else:
                v = np.where(missing, mean, v)
        return v

    def generate(self, init: np.ndarray, n_frames: int, *, n_gibbs: int = 30, seed: int = 0,
                 hidden_noise: float = 0.0, n_samples: int = 1, mean_field: bool = False
                 ) -> np.ndarray:
        """Causal on-line generation from ``init`` (>= order real frames, (n0, D) unnormalised,
        or (S, n0, D) for S different starts generated side by side).

        Returns (n_samples or S, n0 + n_frames, D) unnormalised, starting with ``init``. Each new
        frame starts from the previous one and is refined by ``n_gibbs`` Gibbs updates
        (with hidden probabilities instead of samples if ``mean_field``: deterministic unless
        ``hidden_noise`` > 0).
        """
        n = self.config.order
        init = np.asarray(init)
        if init.ndim == 3:   # (S, n0, D): S different starts, one sequence each
            if n_samples != 1:
                raise MotionlangError("generate: give n_samples=1 with a batch of starts")
            init = np.stack(check_sequences(list(init), self.n_visible, n, "initial frames"))
            x = self.normalise(init)
            n_samples = len(init)
        else:
            init = check_sequences([init], self.n_visible, n, "initial frames")[0]
            x = np.repeat(self.normalise(init)[None], n_samples, axis=0)
        rng = np.random.default_rng(seed)
        n0 = x.shape[1]
        out = np.empty((n_samples, n0 + n_frames, self.n_visible))
        out[:, :n0] = x
        for t in range(n0, n0 + n_frames):
            past = out[:, t - n:t][:, ::-1].reshape(n_samples, -1)
            out[:, t] = self.gibbs_frame(out[:, t - 1], past, rng, n_gibbs,
                                         hidden_noise=hidden_noise, mean_field=mean_field)
        out = self.denormalise(out)
        out[:, :n0] = init   # exactly as given
        return out

    def fill_in(self, frames: np.ndarray, known: np.ndarray, *, n_gibbs: int = 30, seed: int = 0,
                n_samples: int = 1, mean_field: bool = False) -> np.ndarray:
        """Fill the unknown entries of ``frames`` (T, D) on-line, frame by frame.

        ``known`` is a (T, D) or (D,) boolean mask; the first ``order`` frames must be known.
        Unknown entries may hold anything (NaN included). Each frame with a gap starts from
        the previous (filled) frame on its missing dimensions, the known ones are clamped,
        and hidden/visible updates alternate. Known entries come back exactly as given.
        Returns (n_samples, T, D) unnormalised.
        """
        n = self.config.order
        frames = np.asarray(frames, dtype=np.float64)
        known = np.broadcast_to(np.asarray(known, dtype=bool), frames.shape)
        check = np.where(known, frames, 0.0)
        check_sequences([check], self.n_visible, n + 1, "fill-in sequence")
        if not known[:n].all():
            raise MotionlangError(f"fill_in: the first {n} frames (the model order) must be fully known")
        bad = ~np.isfinite(frames) & known
        if bad.any():
            f, d = np.argwhere(bad)[0]
            raise MotionFormatError("<fill-in sequence>", f"non-finite known value in dimension {d}",
                                    frame=int(f))
        rng = np.random.default_rng(seed)
        x = np.repeat(self.normalise(check)[None], n_samples, axis=0)
        for t in range(n, len(frames)):
            missing = ~known[t]
            if not missing.any():
                continue
            start = np.where(missing, x[:, t - 1], x[:, t])
            past = x[:, t - n:t][:, ::-1].reshape(n_samples, -1)
            x[:, t] = self.gibbs_frame(start, past, rng, n_gibbs, missing=missing,
                                       mean_field=mean_field)
        out = self.denormalise(x)
        out[:, known] = frames[known]   # bit-exact, not mean + std * (x - mean) / std
        return out

    def hidden_activations(self, sequences: Sequence[np.ndarray]) -> list[np.ndarray]:
        """p(h | v_t, past) for every frame with a full past: list of (T_i - order, H)."""
        n = self.config.order
        out = []
        for s in check_sequences(sequences, self.n_visible, n + 1):
            x = self.normalise(s)
            rows = np.arange(n, len(x))
            _, b_star = self.dynamic_biases(gather_past(x, rows, n))
            out.append(self.hidden_probs(x[rows], b_star))
        return out

    # ----------------------------------------------------------------- normaliser
    def normalise(self, x: np.ndarray) -> np.ndarray:
        return (np.asarray(x, dtype=np.float64) - self.mean) / self.std

    def denormalise(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x) * self.std + self.mean

    # ----------------------------------------------------------------- save / load
    def save(self, path: str | Path) -> None:
        """One self-describing .npz: config (JSON), parameters, normaliser, training curve."""
        meta = {"kind": "crbm", "version": 1, "config": dataclasses.asdict(self.config),
                "n_visible": self.n_visible}
        arrays = {k: getattr(self, k) for k in PARAMS}
        with atomic_write(path, "wb") as fh:
            np.savez(fh, meta=np.array(json.dumps(meta)), mean=self.mean, std=self.std,
                     history=np.asarray(self.history, dtype=np.float64), **arrays)

    @classmethod
    def load(cls, path: str | Path) -> "CRBM":
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                if meta.get("kind") != "crbm":
                    raise MotionFormatError(path, f"not a CRBM checkpoint (kind={meta.get('kind')!r})")
                model = cls(config_from_dict(meta["config"]), meta["n_visible"])
                for k in PARAMS:
                    setattr(model, k, z[k].astype(model.config.dtype))
                for k in ("mean", "std"):
                    setattr(model, k, z[k].astype(np.float64))
                model.history = z["history"].tolist()
        except (OSError, KeyError, ValueError, TypeError) as exc:
            raise MotionFormatError(path, f"cannot read CRBM checkpoint: {exc}") from exc
        return model

    def describe(self) -> str:
        c = self.config
        return (f"CRBM order {c.order}, {self.n_visible} {c.visible} visible, {c.n_hidden} hidden, "
                f"trained {len(self.history)} epochs"
                + (f", final reconstruction MSE {self.history[-1]:.4f}" if self.history else ""))

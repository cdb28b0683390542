"""The shared, model-agnostic trainer of every gradient-trained motionlang model.

A model only needs ``loss(batch) -> dict[str, Tensor]`` with a scalar ``"loss"`` (a mean
over the batch's items; other entries are logged) and, for self-describing checkpoints,
``to_checkpoint() -> dict`` (otherwise its ``state_dict`` is stored). Data is any sequence
of items plus a ``collate(list_of_items) -> batch`` function.

What it does: NAdam (default) with gradient clipping; a progress bar with loss and
throughput (sequences/s); validation each epoch; ``last.pt`` / ``best.pt`` written
atomically with model, optimizer, every rank's RNG states and the position (epoch, batch,
step), so that ``fit(resume=True)`` continues bit-for-bit like an uninterrupted run with the
same seed; ``history.json`` and ``loss_curve.png``.

Data parallel: launched with ``torchrun --nproc_per_node N`` the trainer joins the gloo
process group, gives each rank an interleaved share of every global batch, and all-reduces
the gradients weighted by share size, so N processes follow the same trajectory as one
process on the same global batches (up to float summation order). Only rank 0 writes files.
The pieces live beside it: :mod:`~motionlang.training.schedule` (learning rate),
:mod:`~motionlang.training.distributed` (process group), :mod:`~motionlang.training.run_files`
(checkpoints, RNG states, loss curve).
"""
from __future__ import annotations

import dataclasses
import json
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any, Protocol, cast

import torch
import torch.distributed as dist

from motionlang.errors import MotionlangError
from motionlang.models.checkpoint import Checkpointed, write_checkpoint
from motionlang.training.config import OPTIMIZER_NAMES, TrainConfig
from motionlang.training.distributed import init_distributed
from motionlang.training.run_files import (
    check_resume,
    check_same_data,
    plot_loss_curve,
    ranked_by,
    read_training_checkpoint,
    rng_state,
    set_rng_state,
)
from motionlang.training.schedule import learning_rate
from motionlang.utils.atomic import atomic_write
from motionlang.utils.progress import progress

log = logging.getLogger(__name__)
OPTIMIZERS = dict(zip(OPTIMIZER_NAMES, (torch.optim.NAdam, torch.optim.Adam,
                                         torch.optim.AdamW, torch.optim.SGD)))


class LossModel(Protocol):
    """What the trainer needs of a model besides ``nn.Module``'s methods."""

    def loss(self, batch: Any) -> dict[str, torch.Tensor]:
        """Named loss terms of a collated batch; ``"loss"`` is the scalar minimised."""
        ...


def check_finite(terms: dict[str, float], model: torch.nn.Module, step: int) -> None:
    """Stop a run whose loss or weights stopped being finite numbers (too high a learning
    rate, bad data): training on would only write checkpoints of NaNs."""
    bad = [k for k, v in terms.items() if not math.isfinite(v)]
    trained = (p for p in model.parameters() if p.requires_grad)   # frozen ones stay as they are
    if not bad and all(bool(torch.isfinite(p).all()) for p in trained):
        return
    what = f"loss term {', '.join(bad)}" if bad else "weights"
    raise MotionlangError(f"training stopped at step {step}: {what} not finite (lower --lr "
                          f"or check the data); the last good checkpoint is kept")


def select_record(scored: float | dict) -> dict[str, float]:
    """What a ``select`` returned -> the validation record's entries: ``{"select": score}``
    and, from a dict, its other measures (numbers)."""
    if not isinstance(scored, dict):
        return {"select": float(scored)}
    if "select" not in scored:
        raise MotionlangError(f"select returned {sorted(scored)}: no 'select' score")
    return {k: float(v) for k, v in scored.items()}


def _fmt(terms: dict[str, float]) -> str:
    return " ".join(f"{k} {v:.4g}" for k, v in terms.items())


class Trainer:
    """Train ``model`` on ``train_set`` (see module docstring).

    Args:
        model: an ``nn.Module`` with ``loss(batch)``.
        train_set, val_set: sequences of items; ``collate`` turns a list of items into a batch.
        config: :class:`TrainConfig`.
        length_of: an item's sequence length, for ``config.length_buckets`` (default:
            ``len(item["motion"])``).
    """

    def __init__(self, model: torch.nn.Module, train_set: Sequence, collate: Callable[[list], Any],
                 config: TrainConfig, val_set: Sequence | None = None,
                 length_of: Callable[[Any], int] | None = None,
                 select: Callable[[torch.nn.Module], float | dict] | None = None,
                 on_epoch: Callable[[dict], None] | None = None):
        """``select``: model -> a validation score, lower is better, that picks ``best.pt``
        instead of the validation loss (recorded as ``val["select"]``; e.g. the evaluator's
        R-precision, which its contrastive loss follows badly on templated captions), or a
        dict with that score under ``"select"`` and other measures to record beside it.
        ``on_epoch``: called on every rank with each epoch's history record, once its
        checkpoints are written (e.g. a recipe's own progress line)."""
        if len(train_set) == 0:
            raise MotionlangError("training set is empty")
        self.model, self.train_set, self.val_set = model, train_set, val_set
        self.collate, self.config, self.select = collate, config, select
        self.on_epoch = on_epoch
        self._lengths = None
        if config.length_buckets > 0:
            length_of = length_of or (lambda item: len(item["motion"]))
            self._lengths = [int(length_of(item)) for item in train_set]
        self.out_dir = Path(config.out_dir)
        self.rank, self.world = init_distributed()
        if self.world > 1:  # every rank starts from rank 0's weights
            for p in model.parameters():
                dist.broadcast(p.data, 0)
        self.optimizer = OPTIMIZERS[config.optimizer](model.parameters(), lr=config.lr,
                                                      weight_decay=config.weight_decay)
        self.history: list[dict] = []

    # -- data ---------------------------------------------------------------------------
    def _batches(self, epoch: int) -> list[list[int]]:
        """The epoch's global batches, a function of (seed, epoch) only."""
        g = torch.Generator().manual_seed(self.config.seed * 100_003 + epoch)
        perm = torch.randperm(len(self.train_set), generator=g).tolist()
        bs = self.config.batch_size
        if self._lengths is None:
            return [perm[i:i + bs] for i in range(0, len(perm), bs)]
        pool = bs * self.config.length_buckets
        batches = []
        for i in range(0, len(perm), pool):
            chunk = sorted(perm[i:i + pool], key=self._lengths.__getitem__)
            batches += [chunk[j:j + bs] for j in range(0, len(chunk), bs)]
        order = torch.randperm(len(batches), generator=g).tolist()
        return [batches[k] for k in order]

    def _share(self, idx: list[int]) -> list[int]:
        return idx[self.rank::self.world]

    # -- one step -----------------------------------------------------------------------
    def _decay_steps(self, n_batches: int) -> int:
        d = self.config.decay_epochs
        return max(1, round(d * n_batches)) if d > 0 else 0

    def _set_lr(self, epoch: int, batch: int, n_batches: int) -> float:
        c = self.config
        lr = learning_rate(c.lr, epoch * n_batches + batch, c.epochs * n_batches,
                           self._decay_steps(n_batches), c.decay_to)
        for group in self.optimizer.param_groups:
            group["lr"] = lr
        return lr

    def _loss(self, batch: Any) -> dict[str, torch.Tensor]:
        return cast(LossModel, self.model).loss(batch)

    def _train_step(self, idx: list[int]) -> dict[str, float]:
        mine = self._share(idx)
        self.model.train()
        self.optimizer.zero_grad(set_to_none=False)
        for p in self.model.parameters():
            if not p.requires_grad:
                # a part frozen after an earlier stage keeps a zeroed gradient, and AdamW
                # decays every parameter that has one: a frozen parameter must have none
                p.grad = None
        terms: dict[str, float] = {}
        if mine:
            out = self._loss(self.collate([self.train_set[i] for i in mine]))
            out["loss"].backward()
            terms = {k: float(v.detach()) for k, v in out.items()}
        params = [p for p in self.model.parameters() if p.requires_grad]
        if self.world > 1:
            # Weight each rank's mean-gradient by its share so the sum is the global mean.
            # A rank with an empty share (last batch smaller than the world) sends zeros.
            flat = torch.cat([(p.grad if p.grad is not None else torch.zeros_like(p)).reshape(-1)
                              for p in params]) * (len(mine) / len(idx))
            dist.all_reduce(flat)
            off = 0
            for p in params:
                n = p.numel()
                p.grad = flat[off:off + n].view_as(p).clone()
                off += n
        if self.config.grad_clip:
            torch.nn.utils.clip_grad_norm_(params, self.config.grad_clip)
        self.optimizer.step()
        return terms

    def _reduce(self, sums: dict[str, float], count: float) -> dict[str, float]:
        """Item-weighted means of loss terms over all ranks."""
        keys = sorted(sums)
        if self.world > 1:
            t = torch.tensor([count] + [sums[k] for k in keys], dtype=torch.float64)
            dist.all_reduce(t)
            count, vals = float(t[0]), t[1:].tolist()
        else:
            vals = [sums[k] for k in keys]
        return {k: v / count for k, v in zip(keys, vals)} if count else {}

    @torch.no_grad()
    def validate(self) -> dict[str, float]:
        """Item-weighted mean of every loss term over the validation set (all ranks)."""
        if not self.val_set:
            return {}
        self.model.eval()
        sums: dict[str, float] = {}
        count = 0
        order = list(range(len(self.val_set)))
        bs = self.config.batch_size
        for i in range(0, len(order), bs):
            mine = self._share(order[i:i + bs])
            if not mine:
                continue
            out = self._loss(self.collate([self.val_set[j] for j in mine]))
            for k, v in out.items():
                sums[k] = sums.get(k, 0.0) + float(v) * len(mine)
            count += len(mine)
        return self._reduce(sums, count)

    # -- checkpoints --------------------------------------------------------------------
    def _model_dict(self) -> dict:
        if hasattr(self.model, "to_checkpoint"):   # a self-describing model
            return cast(Checkpointed, self.model).to_checkpoint()
        return {"kind": type(self.model).__name__, "state_dict": self.model.state_dict()}

    def _save(self, name: str, pos: dict) -> None:
        rng = [rng_state()]
        if self.world > 1:
            gathered: list = [None] * self.world
            dist.all_gather_object(gathered, rng[0])
            rng = gathered
        if self.rank != 0:
            return
        write_checkpoint({"model": self._model_dict(), "optimizer": self.optimizer.state_dict(),
                          "rng": rng, "world_size": self.world, "history": self.history,
                          "train_config": asdict(self.config), "n_train": len(self.train_set),
                          **pos}, self.out_dir / name)

    def _load(self, path: Path) -> dict:
        ck = read_training_checkpoint(path)
        check_same_data(path, ck["model"], self._model_dict())
        try:
            self.model.load_state_dict(ck["model"]["state_dict"])
        except RuntimeError as exc:   # e.g. another vocabulary size or model size
            raise MotionlangError(f"{path}: the model built from these options does not fit "
                                  f"the checkpoint's weights (other sizes or vocabulary?): "
                                  f"{str(exc).splitlines()[0]}") from exc
        self.optimizer.load_state_dict(ck["optimizer"])
        if ck["world_size"] == self.world:
            set_rng_state(ck["rng"][self.rank])
        else:
            log.warning("%s was written by %d processes, now %d: RNG streams restart",
                        path, ck["world_size"], self.world)
            torch.manual_seed(self.config.seed + self.rank + ck["step"])
        self.history = list(ck["history"])
        return ck

    def _config_changed(self, old: dict | None) -> bool:
        """Does the model's config differ from a checkpoint's (``old``)? Fields the checkpoint
        predates count as their defaults."""
        new = self._model_dict().get("config")
        if old is None or new is None:
            return old != new
        cfg = getattr(self.model, "config", None)
        defaults = {}
        if dataclasses.is_dataclass(cfg):
            for f in dataclasses.fields(cfg):
                if f.default is not dataclasses.MISSING:
                    defaults[f.name] = f.default
                elif f.default_factory is not dataclasses.MISSING:
                    defaults[f.name] = f.default_factory()
        return any(old.get(k, defaults.get(k)) != v for k, v in new.items())

    def _check_batching(self, ck: dict, path: Path) -> None:
        """A mid-epoch resume continues the interrupted epoch's batch list: the options that
        make that list must not have changed."""
        if not ck["batch"]:
            return
        old, new = ck.get("train_config", {}), asdict(self.config)
        changed = [k for k in ("batch_size", "seed", "length_buckets")
                   if old.get(k, 0 if k == "length_buckets" else None) != new[k]]
        if ck.get("n_train", len(self.train_set)) != len(self.train_set):
            changed.append(f"training set size ({ck['n_train']} -> {len(self.train_set)})")
        if changed:
            raise MotionlangError(f"{path}: interrupted in the middle of an epoch with other "
                                  f"{', '.join(changed)}; resume with the same values")

    # -- the loop -----------------------------------------------------------------------
    def fit(self, resume: bool = False) -> list[dict]:
        """Train for ``config.epochs`` epochs; with ``resume`` continue from ``last.pt``.

        Returns the history: one dict per epoch with ``epoch``, ``step``, ``train`` and
        ``val`` loss terms, ``seq_per_s`` and ``lr`` (the rate of its last step).
        """
        c = self.config
        epoch, start_batch, step = 0, 0, 0
        sums, count, best = {}, 0, math.inf
        last = self.out_dir / "last.pt"
        if resume:
            ck = self._load(check_resume(self.out_dir, read=False))
            epoch, start_batch, step = ck["epoch"], ck["batch"], ck["step"]
            sums, count, best = dict(ck["epoch_sums"]), ck["epoch_count"], ck["best"]
            self._check_batching(ck, last)
            ranked = ranked_by(ck)
            if ranked != self._best_by():
                log.warning("%s ranked best.pt by %s, this run by %s: best.pt is chosen "
                            "among the epochs from here on", last, ranked, self._best_by())
                best = math.inf
            elif math.isfinite(best) and not (self.out_dir / "best.pt").is_file():
                log.warning("%s: its best.pt is missing; best.pt is chosen among the epochs "
                            "from here on", self.out_dir)
                best = math.inf
            elif self._config_changed(ck["model"].get("config")):
                # e.g. resumed with other loss weights: the old best score measured another
                # loss, so best.pt is ranked afresh from here on
                log.warning("%s: the model's config differs from the checkpoint's; best.pt "
                            "is chosen among the epochs from here on", last)
                best = math.inf
            log.info("resuming from %s at epoch %d batch %d", last, epoch + 1, start_batch)
            if 0 < c.decay_epochs and c.epochs - c.decay_epochs < epoch:
                log.warning("the learning-rate decay began at epoch %g, before this resume: "
                            "the rate drops at once", c.epochs - c.decay_epochs + 1)
        hide = True if self.rank else (None if c.progress is None else not c.progress)
        while epoch < c.epochs:
            batches = self._batches(epoch)
            bar = progress(total=len(batches), initial=start_batch, unit="batch",
                           desc=f"epoch {epoch + 1}/{c.epochs}", disable=hide)
            t0, seen = time.perf_counter(), 0
            lr = c.lr
            for b in range(start_batch, len(batches)):
                lr = self._set_lr(epoch, b, len(batches))
                terms = self._train_step(batches[b])
                check_finite(terms, self.model, step + 1)
                n = len(self._share(batches[b]))
                for k, v in terms.items():
                    sums[k] = sums.get(k, 0.0) + v * n
                count += n
                step += 1
                seen += len(batches[b])
                bar.update(1)
                bar.set_postfix(loss=f"{terms.get('loss', float('nan')):.4g}",
                                seq_s=f"{seen / max(time.perf_counter() - t0, 1e-9):.0f}")
                if c.checkpoint_every and step % c.checkpoint_every == 0 and b + 1 < len(batches):
                    self._save("last.pt", {"epoch": epoch, "batch": b + 1, "step": step,
                                           "epoch_sums": sums, "epoch_count": count, "best": best,
                                           "best_by": self._best_by()})
            bar.close()
            rate = seen / max(time.perf_counter() - t0, 1e-9)
            train, val = self._reduce(sums, count), self.validate()
            if val and self.select is not None:   # every rank: the same weights, same score
                with torch.no_grad():
                    scored = self.select(self.model.eval())
                val.update(select_record(scored))
            self.history.append({"epoch": epoch + 1, "step": step, "train": train, "val": val,
                                 "seq_per_s": rate, "lr": lr})
            log.info("epoch %d/%d: train %s | val %s | %.0f seq/s | lr %.3g", epoch + 1,
                     c.epochs, _fmt(train), _fmt(val) or "-", rate, lr)
            epoch, start_batch, sums, count = epoch + 1, 0, {}, 0
            score = (val or train).get("select" if "select" in (val or {}) else "loss",
                                       math.inf)
            pos = {"epoch": epoch, "batch": 0, "step": step, "epoch_sums": {}, "epoch_count": 0,
                   "best_by": self._best_by()}
            if score < best:
                best = score
                self._save("best.pt", {**pos, "best": best})
            self._save("last.pt", {**pos, "best": best})
            if self.rank == 0:
                self._write_history()
            if self.on_epoch is not None:
                self.on_epoch(self.history[-1])
        return self.history

    def _best_by(self) -> str:
        """What ranks ``best.pt``: the ``select`` score (its ``key`` where it has one: what
        it scores, on what, so that the scores of another selector are not compared with
        it), else the (validation) loss."""
        if self.select is None or not self.val_set:
            return "loss"
        return str(getattr(self.select, "key", "select"))

    def _write_history(self) -> None:
        with atomic_write(self.out_dir / "history.json") as fh:
            json.dump(self.history, fh, indent=1)
        if self.config.plot:
            plot_loss_curve(self.history, self.out_dir / "loss_curve.png")

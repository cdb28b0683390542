"""A tiny regression model and data for the trainer tests, runnable under torchrun.

    torchrun --standalone --nproc_per_node 2 tests/helpers/trainer_tiny.py OUT_DIR

trains with the Trainer and saves each rank's final weights as OUT_DIR/rank{r}.pt.
"""
from __future__ import annotations

import sys
from pathlib import Path

import torch
from torch import nn

from motionlang.training.distributed import finish_distributed
from motionlang.training.trainer import TrainConfig, Trainer


class TinyReg(nn.Module):
    """x (B, 4) -> y (B,); mean squared error, so batch gradients are item means."""

    def __init__(self, dropout: float = 0.0, fail_after: int | None = None):
        super().__init__()
        self.net = nn.Sequential(nn.Linear(4, 16), nn.Tanh(), nn.Dropout(dropout),
                                 nn.Linear(16, 1))
        self.calls, self.fail_after = 0, fail_after

    def loss(self, batch):
        if self.training:
            self.calls += 1
            if self.fail_after is not None and self.calls > self.fail_after:
                raise KeyboardInterrupt("simulated interruption")
        x, y = batch
        err = self.net(x).squeeze(-1) - y
        return {"loss": (err ** 2).mean(), "mae": err.abs().mean().detach()}


def make_data(n: int = 40, seed: int = 0) -> list[tuple[torch.Tensor, torch.Tensor]]:
    g = torch.Generator().manual_seed(seed)
    x = torch.randn(n, 4, generator=g)
    y = torch.sin(x[:, 0]) + 0.5 * x[:, 1] * x[:, 2]
    return [(x[i], y[i]) for i in range(n)]


def collate(items):
    return torch.stack([i[0] for i in items]), torch.stack([i[1] for i in items])


def ddp_config(out_dir) -> TrainConfig:
    return TrainConfig(epochs=3, batch_size=8, lr=1e-2, seed=3, grad_clip=1.0,
                       out_dir=str(out_dir), plot=False, progress=False)


def main(out: Path) -> None:
    torch.set_num_threads(1)
    torch.manual_seed(0)
    model = TinyReg()
    # 41 items in batches of 8: the last batch has 1 item, so rank 1's share is empty
    trainer = Trainer(model, make_data(41), collate, ddp_config(out / "run"),
                      val_set=make_data(16, 1))
    trainer.fit()
    torch.save(model.state_dict(), out / f"rank{trainer.rank}.pt")
    if trainer.rank == 0:
        torch.save(trainer.history, out / "history.pt")
    finish_distributed()


if __name__ == "__main__":
    main(Path(sys.argv[1]))

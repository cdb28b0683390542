"""Data-parallel training under ``torchrun``: joining and leaving the gloo process group.

Outside torchrun (no ``WORLD_SIZE`` > 1) every function here is a no-op and the process is
rank 0 of a world of one.
"""
from __future__ import annotations

import os

import torch.distributed as dist


def init_distributed() -> tuple[int, int]:
    """Join the gloo process group when started by torchrun; returns (rank, world_size)."""
    if int(os.environ.get("WORLD_SIZE", "1")) > 1 and not dist.is_initialized():
        dist.init_process_group("gloo")
    if dist.is_initialized():
        return dist.get_rank(), dist.get_world_size()
    return 0, 1


def finish_distributed() -> None:
    """Leave the process group together: every rank waits at a barrier, then tears it down.

    Without the barrier a rank that finishes first (the others still writing checkpoints or
    plots) can tear down its gloo connections under them, and the process aborts at exit.
    No-op outside torchrun.
    """
    if dist.is_initialized():
        dist.barrier()
        dist.destroy_process_group()

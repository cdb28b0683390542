"""Indexing on Ray (the ``ray`` extra): ``index DIR -o FILE --engine ray --workers N``.

The files the index has to embed (those new or changed: the same digests and the same
skip-what-did-not-change rule as on one machine) are read, analysed and embedded by ``N``
Ray actors, each loading the model once, on the cluster ``RAY_ADDRESS`` names or, without
it, on a Ray started on this machine for the run. Results come back in the folder's order,
so the index is the one a single process makes. For an archive beyond what one machine
holds at once, index shards (``--shard K/N``) and join them (``merge-index``).
"""
from __future__ import annotations

import importlib.util
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.library.embedder import Embedder


def available() -> bool:
    return importlib.util.find_spec("ray") is not None


class _Worker:
    """One actor: the model loaded once, then one file after another (``embed``:
    ``library.index.embed_file``, sent by reference)."""

    def __init__(self, model: Any, threads: int, embed: Callable[[Any, Any], Any]):
        import torch
        torch.set_num_threads(threads)
        self.embedder = Embedder.load(model)
        self.run = embed

    def embed(self, job: Any) -> Any:
        return job, self.run(self.embedder, job)


def embedded_on_ray(jobs: list, model: Any, workers: int, embed: Callable[[Any, Any], Any]
                    ) -> Iterator[tuple[Any, Any]]:
    """``(job, result)`` of each job, in order, by ``workers`` Ray actors, each running
    ``embed(embedder, job)``.

    Raises:
        MotionlangError: ray is not installed.
    """
    try:
        import ray
        from ray.util import ActorPool
    except ImportError:
        raise MotionlangError("--engine ray needs the ray package (pip install "
                              "'motionlang[ray]')") from None
    started = not ray.is_initialized()
    scratch = None
    if started:
        address = os.environ.get("RAY_ADDRESS")
        # a Ray started for this run keeps its logs and sockets in a folder of its own,
        # removed after it (Ray's default folder, /tmp/ray, keeps those of every start)
        scratch = None if address else tempfile.mkdtemp(prefix="motionlang-ray-")
        extra: dict[str, Any] = {"_temp_dir": scratch} if scratch else {}
        ray.init(address=address, num_cpus=None if address else workers,
                 include_dashboard=False, log_to_driver=False, ignore_reinit_error=True,
                 **extra)
    try:
        actor = ray.remote(num_cpus=1)(_Worker)
        pool = ActorPool([actor.remote(model, 1, embed) for _ in range(max(1, workers))])
        yield from pool.map(lambda a, job: a.embed.remote(job), jobs)
    finally:
        if started:
            ray.shutdown()
        if scratch:
            shutil.rmtree(scratch, ignore_errors=True)

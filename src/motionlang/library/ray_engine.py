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
from collections.abc import Callable, Iterator
from pathlib import Path
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
    session = None
    if started:
        address = os.environ.get("RAY_ADDRESS")
        ray.init(address=address, num_cpus=None if address else workers,
                 include_dashboard=False, log_to_driver=False, ignore_reinit_error=True)
        # a Ray started here for this run: its folder of logs and sockets goes with it
        session = None if address else _run_folder(ray)
    try:
        actor = ray.remote(num_cpus=1)(_Worker)
        pool = ActorPool([actor.remote(model, 1, embed) for _ in range(max(1, workers))])
        yield from pool.map(lambda a, job: a.embed.remote(job), jobs)
    finally:
        if started:
            ray.shutdown()
        if session is not None:
            _remove_run_folder(session)


def _run_folder(ray: Any) -> Path | None:
    """The folder of logs and sockets of the Ray this process started, where this Ray
    version says (no public call tells it; None where the private one is gone: the folder
    is kept)."""
    try:
        return Path(ray._private.worker._global_node.get_session_dir_path())
    except Exception:   # noqa: BLE001 - a Ray without it keeps its folder, as Ray does
        return None


def _remove_run_folder(folder: Path) -> None:
    """Remove the folder of a Ray that has shut down, and Ray's link to it as the latest."""
    if not folder.name.startswith("session_") or not folder.is_dir():
        return   # not a name Ray gives such folders: left alone
    latest = folder.parent / "session_latest"
    if latest.is_symlink() and Path(os.readlink(latest)).name == folder.name:
        latest.unlink(missing_ok=True)
    shutil.rmtree(folder, ignore_errors=True)

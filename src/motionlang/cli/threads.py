"""``--threads N`` of every command: how many threads torch and numpy's BLAS may use.

The default follows ``benchmarks/bench_threads.py`` (figures in ``docs/results/seq2seq.md``,
Threads): on an idle machine a second thread speeds work up, but on a CPU that is already busy
extra threads fight the other work and cost many times what they win when idle. So: one
thread as soon as the 1-minute load average is near the number of CPUs, else up to
:data:`MAX_DEFAULT` (the models are small LSTMs, which gain little from many threads).
"""
from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator

#: the default never exceeds this many threads (the models are small: more buys little)
MAX_DEFAULT = 4
#: "busy": the 1-minute load average within this many CPUs of their number
BUSY_MARGIN = 0.5
#: the environment variables the OpenMP / BLAS libraries read when they load
THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def default_threads(load: float | None = None, cpus: int | None = None) -> int:
    """Threads for a command run without ``--threads``: ``OMP_NUM_THREADS`` if the user set
    it, else 1 on a busy CPU (1-minute load average >= CPUs - :data:`BUSY_MARGIN`), else
    min(CPUs, :data:`MAX_DEFAULT`)."""
    env = os.environ.get("OMP_NUM_THREADS", "")
    if env.isdigit() and int(env) >= 1:
        return int(env)
    cpus = cpus or os.cpu_count() or 1
    if load is None:
        try:
            load = os.getloadavg()[0]
        except OSError:   # not available on this platform
            load = 0.0
    if load >= cpus - BUSY_MARGIN:
        return 1
    return max(1, min(cpus, MAX_DEFAULT))


@contextlib.contextmanager
def limit_threads(n: int) -> Iterator[None]:
    """Run the body with ``n`` threads for torch (``set_num_threads`` when it is loaded, the
    OpenMP variables it reads on import when it is not yet) and for numpy's BLAS
    (threadpoolctl). torch's count is restored afterwards when it was loaded before."""
    torch = sys.modules.get("torch")
    old_torch = torch.get_num_threads() if torch is not None else None
    old_env = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    if torch is not None:
        torch.set_num_threads(n)
    else:
        os.environ.update({k: str(n) for k in THREAD_VARIABLES})
    try:
        from threadpoolctl import threadpool_limits
        limits = threadpool_limits(limits=n, user_api="blas")
    except ImportError:   # threadpoolctl is a dependency; tolerate its absence anyway
        limits = contextlib.nullcontext()
    try:
        with limits:
            yield
    finally:
        for k, v in old_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
        if old_torch is not None:
            torch.set_num_threads(old_torch)

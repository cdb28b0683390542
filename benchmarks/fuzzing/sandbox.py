"""A child process that runs one reader at a time on untrusted bytes, under limits.

The parent (:class:`Sandbox`) writes each input to a file in its own temporary folder and
sends the child one JSON line; the child reads the file with the format's reader, checks
what came back and answers one JSON line. The outcome (:data:`KINDS`):

* ``error``: a ``MotionlangError`` whose message is one line starting with the file's path,
  the one acceptable failure;
* ``valid``: a Motion (for ASF a Skeleton) with consistent shapes, finite values and finite
  joint positions (for ``h3d``, a HumanML3D-layout folder unpacked from the input's tar:
  ``load_h3d`` and, for its first records, rows, joints and a Motion, all such);
* ``invalid``: a value that is not that, or an error message that does not name the file;
* ``uncaught``: any other exception (MemoryError included: readers must refuse first);
* ``crash``: the child died (SIGSEGV, SIGBUS, an abort); it is started again;
* ``hang``: no answer within ``time_limit`` seconds; the child is killed and started again.

The child's address space is capped (``RLIMIT_AS``) at what it uses once started plus
``memory_bytes``, and its ``MOTIONLANG_MAX_MEMORY`` is a quarter of ``memory_bytes``: a reader
that checks what it asks for refuses before the cap, one that does not gets a MemoryError
instead of swapping the machine. Unix only (``resource``, ``select`` on pipes).
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

from .sidecars import EXTENSIONS as SIDECAR_EXTENSIONS
from .sidecars import SIDECARS, read_sidecar

KINDS = ("error", "valid", "invalid", "uncaught", "crash", "hang")
EXTENSIONS = {"asf": ".asf", "amc": ".amc", "bvh": ".bvh", "mmm": ".xml", "mit": ".mat",
              "h3d": ".tar", **SIDECAR_EXTENSIONS}
H3D_RECORDS = 4  # records of an h3d folder whose rows, joints and Motion are read
# The child imports this module by the name it has here, from the folder that name is
# relative to (``benchmarks/`` for ``fuzzing.sandbox``).
_CHILD = f"from {__name__} import serve; serve()"
_IMPORT_ROOT = Path(__file__).resolve().parents[__name__.count(".")]


@dataclass
class Outcome:
    """What became of one input: ``kind`` (one of :data:`KINDS`), a one-line ``detail``
    (the error message, the exception and where, the signal...) and the ``seconds`` taken."""
    kind: str
    detail: str = ""
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return self.kind in ("error", "valid")


class Sandbox:
    """Runs readers in a child process (started on first use; use as a context manager or
    call :meth:`close`).

    Args:
        memory_bytes: address space the child may add to what it uses after start-up.
        time_limit: seconds one input may take.
    """

    def __init__(self, memory_bytes: int = 1 << 30, time_limit: float = 10.0):
        self.memory_bytes, self.time_limit = int(memory_bytes), float(time_limit)
        self.folder = Path(tempfile.mkdtemp(prefix="motionlang-fuzz-"))
        self.proc: subprocess.Popen | None = None
        self.starts = 0
        self._buf = b""

    def __enter__(self) -> Sandbox:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop the child and remove the temporary folder."""
        self._stop()
        shutil.rmtree(self.folder, ignore_errors=True)

    # ------------------------------------------------------------------ child process
    def _start(self) -> None:
        env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
                   MKL_NUM_THREADS="1", PYTHONFAULTHANDLER="1",
                   MOTIONLANG_MAX_MEMORY=str(self.memory_bytes // 4))
        # the child reads with the parent's motionlang, not whichever one it would find
        motionlang_root = str(Path(importlib.util.find_spec("motionlang").origin).parents[1])
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (str(_IMPORT_ROOT), motionlang_root, env.get("PYTHONPATH")) if p)
        self._err = open(self.folder / "child.err", "w+b")
        self.proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(self.memory_bytes)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self._err, env=env, cwd=self.folder)
        self.starts += 1
        self._buf = b""
        reply = self._read(120.0)
        if not isinstance(reply, dict) or reply.get("kind") != "ready":
            tail = self._stderr_tail()
            self._stop()
            raise RuntimeError(f"the fuzzing child process did not start: {tail}")

    def _stop(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()
            for f in (self.proc.stdin, self.proc.stdout):
                with contextlib.suppress(OSError):  # unsent bytes to a dead child
                    f.close()
            self._err.close()
            self.proc = None

    def _read(self, timeout: float):
        """The child's next JSON line, ``"timeout"``, or None if it died."""
        deadline = time.monotonic() + timeout
        while b"\n" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                return "timeout"
            ready, _, _ = select.select([self.proc.stdout], [], [], left)
            if ready:
                chunk = os.read(self.proc.stdout.fileno(), 1 << 16)
                if not chunk:
                    return None
                self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        return json.loads(line)

    def _stderr_tail(self) -> str:
        self._err.seek(0)
        lines = [ln.strip() for ln in self._err.read().decode(errors="replace").splitlines()]
        where = [ln for ln in lines if ln.startswith("File ")]
        return " | ".join((lines[:1] + where[:3]) if where else lines[-3:])[:600]

    # ------------------------------------------------------------------ one input
    def run(self, fmt: str, data: bytes, skeleton: bytes | None = None) -> Outcome:
        """Read ``data`` as format ``fmt`` (``asf``, ``amc``, ``bvh``, ``mmm``, ``mit``, ``h3d``:
        a tar of a HumanML3D-layout folder, :func:`.seeds.pack_h3d`); for ``amc`` pass the ASF
        text as ``skeleton``."""
        if self.proc is None:
            self._start()
        body = None
        if fmt == "h3d":
            from .seeds import unpack_h3d
            body, files = unpack_h3d(data)
            path = self.folder / "h3d"
            shutil.rmtree(path, ignore_errors=True)
            path.mkdir()
            for name, content in files.items():
                (path / name).parent.mkdir(parents=True, exist_ok=True)
                (path / name).write_bytes(content)
        else:
            path = self.folder / f"input{EXTENSIONS[fmt]}"
            path.write_bytes(data)
        asf = None
        if skeleton is not None:
            asf = self.folder / f"skeleton-{hashlib.sha1(skeleton).hexdigest()[:16]}.asf"
            if not asf.exists():
                asf.write_bytes(skeleton)
        request = json.dumps({"fmt": fmt, "path": str(path), "asf": asf and str(asf),
                              "body": body})
        t0 = time.monotonic()
        try:
            self.proc.stdin.write(request.encode() + b"\n")
            self.proc.stdin.flush()
            reply = self._read(self.time_limit)
        except BrokenPipeError:
            reply = None
        seconds = time.monotonic() - t0
        if reply == "timeout":
            self._stop()
            return Outcome("hang", f"no answer within {self.time_limit:g} s", seconds)
        if reply is None:
            code = self.proc.wait()
            how = signal.Signals(-code).name if code < 0 else f"exit status {code}"
            detail = f"child died ({how}): {self._stderr_tail()}"
            self._stop()
            return Outcome("crash", detail, seconds)
        return Outcome(reply["kind"], reply["detail"], seconds)


# ---------------------------------------------------------------------- the child's side
def _limit_memory(headroom: int) -> None:
    import resource
    try:
        with open("/proc/self/status") as fh:
            vm = next(int(ln.split()[1]) * 1024 for ln in fh if ln.startswith("VmSize:"))
    except (OSError, StopIteration, ValueError):
        vm = 0
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = vm + headroom
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))


def _check(result) -> str | None:
    """Why ``result`` is not a valid reading (None if it is)."""
    import numpy as np

    from motionlang.kinematics import Motion, Skeleton
    if isinstance(result, Skeleton):
        ok = np.all(np.isfinite(result.offsets)) and np.isfinite(result.file_unit) \
            and result.file_unit > 0
        return None if ok else "skeleton with non-finite offsets or unit"
    motions = result if isinstance(result, list) else [result]
    if not motions or not all(isinstance(m, Motion) for m in motions):
        return f"returned {type(result).__name__}, not a Motion"
    for m in motions:
        T = m.n_frames
        shapes = (m.root_translation.shape == (T, 3) and m.joint_angles.shape ==
                  (T, m.skeleton.ndof) and m.root_rotation.shape == (T, len(m.skeleton.root_axes)))
        if T < 1 or not (np.isfinite(m.fps) and m.fps > 0) or not shapes:
            return f"inconsistent motion: {T} frames at {m.fps} fps, shapes do not agree"
        for arr in (m.root_translation, m.root_rotation, m.joint_angles, m.positions()):
            if not np.all(np.isfinite(arr)):
                return "motion with non-finite values or joint positions"
    return None


class _Invalid(Exception):
    """A reading that returned something other than what it promises."""


def _read_h3d(req: dict):
    """``load_h3d`` of the folder; rows, joints and a Motion of its first records."""
    import numpy as np

    from motionlang.datasets.humanml3d import load_h3d
    records = load_h3d(req["path"], req["body"], mirrored=True)
    motions = []
    for rec in records[:H3D_RECORDS]:
        rows, joints = rec.load_vectors(), rec.load_joints()
        b = rec.body
        if rows.ndim != 2 or rows.shape[1] != b.dim or not len(rows) or \
                joints.shape != (len(joints), b.n_joints, 3) or not len(joints):
            raise _Invalid(f"{rec.id}: rows {rows.shape}, joints {joints.shape}")
        if not (np.isfinite(rows).all() and np.isfinite(joints).all()):
            raise _Invalid(f"{rec.id}: non-finite rows or joints")
        motions.append(rec.load_motion())
    return motions


def _read(req: dict, skeletons: dict):
    from motionlang.formats.asf_amc import read_amc, read_asf
    from motionlang.formats.bvh import read_bvh
    from motionlang.formats.mit import read_mit
    from motionlang.formats.mmm import read_mmm
    fmt, path = req["fmt"], req["path"]
    if fmt == "h3d":
        return _read_h3d(req)
    if fmt in SIDECARS:   # what they return is checked by their readers' own schemas
        read_sidecar(fmt, path)
        return None
    if fmt == "amc":
        if req["asf"] not in skeletons:
            skeletons[req["asf"]] = read_asf(req["asf"])
        return read_amc(path, skeletons[req["asf"]])
    return {"asf": read_asf, "bvh": read_bvh, "mmm": read_mmm, "mit": read_mit}[fmt](path)


def _one(req: dict, skeletons: dict) -> tuple[str, str]:
    from motionlang.errors import MotionlangError
    try:
        result = _read(req, skeletons)
        problem = None if req["fmt"] in SIDECARS else _check(result)
    except _Invalid as exc:
        return "invalid", str(exc)
    except MotionlangError as exc:
        msg = str(exc)
        if "\n" in msg or not msg.startswith(req["path"]):
            return "invalid", f"error message is not one line naming the file: {msg!r}"
        return "error", msg
    except Exception as exc:  # noqa: BLE001 - what the fuzzing is looking for
        frame = traceback.extract_tb(exc.__traceback__)[-1]
        return "uncaught", (f"{type(exc).__name__}: {str(exc)[:200]} (at "
                            f"{Path(frame.filename).name}:{frame.lineno})")
    return ("invalid", problem) if problem else ("valid", "")


def serve() -> None:
    """The child's loop: one JSON request per line on stdin, one answer per line."""
    proto = os.fdopen(os.dup(1), "wb", buffering=0)
    os.dup2(2, 1)  # whatever a reader prints goes to stderr, not into the answers
    sys.stdout = sys.stderr
    import warnings

    import torch  # noqa: F401

    import motionlang.datasets.custom  # noqa: F401 - the sidecar readers
    import motionlang.datasets.humanml3d  # noqa: F401
    import motionlang.features.joint_map  # noqa: F401
    import motionlang.formats.asf_amc  # noqa: F401 - imported before the memory cap
    import motionlang.formats.bvh  # noqa: F401
    import motionlang.formats.gltf_read  # noqa: F401
    import motionlang.formats.mit  # noqa: F401
    import motionlang.formats.mmm  # noqa: F401
    import motionlang.kinematics.from_positions  # noqa: F401
    import motionlang.library.store  # noqa: F401
    import motionlang.models.registry  # noqa: F401
    warnings.simplefilter("ignore")  # a warning is not a failure; its text is not wanted
    _limit_memory(int(sys.argv[1]))
    proto.write(b'{"kind": "ready"}\n')
    skeletons: dict = {}
    for line in sys.stdin.buffer:
        kind, detail = _one(json.loads(line), skeletons)
        proto.write(json.dumps({"kind": kind, "detail": detail[:600]}).encode() + b"\n")

"""A bounded HTTP fuzz of every route of ``motionlang serve`` (issue 58): N requests mutated
from valid ones (``fuzzing/http.py``), sent one at a time over loopback to the server run
as a user runs it, in its own process, from an empty working folder with its own TMPDIR.

The bar: 0 answers of 5xx, 0 errors that are not one line of JSON, 0 foreign ``Host`` or
cross-site ``Origin`` served, 0 hangs (``--timeout``), the server up throughout (its process
alive and ``/api/info`` answering after every ``--check-every`` requests), and no file left
in its TMPDIR or working folder when it stops. The index it searches is built first from
three generated takes (or ``--library DIR``). Prints the outcomes per route, the slowest
answers, the first examples of each fault, the server's log lines of any traceback, and
exits 1 if the bar is missed. Reproducible from ``--seed``.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/fuzz_serve.py [N] [--seed S] \\
        [--model l2m-procedural] [--describe-model m2l-procedural]
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")   # one core, set before numpy loads its BLAS

import argparse  # noqa: E402
import re  # noqa: E402
import signal  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections import Counter, defaultdict  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DATA  # noqa: E402
from fuzzing.http import FAULTS, ROUTES, Fuzzer, Request, outcome, send, upload_seeds  # noqa: E402

import motionlang.api as ml  # noqa: E402
from motionlang.rendering.output import write_result  # noqa: E402

LIBRARY_TAKES = ("a person walks forward", "a person jumps", "a person waves")


def build_library(folder: Path, model: str) -> Path:
    """Three generated takes as BVH files under ``folder``."""
    folder.mkdir(parents=True)
    for i, text in enumerate(LIBRARY_TAKES):
        motion = ml.generate(text, model, seed=i)
        write_result(motion, folder / f"{text.split()[2]}.bvh", fps=motion.fps, title=text)
    return folder


def start_server(args, work: Path, index: Path) -> tuple[subprocess.Popen, str, Path]:
    """``motionlang serve`` on a free loopback port: its process, URL and log file."""
    exe = Path(sys.executable).with_name("motionlang")
    cmd = [str(exe), "serve", "--port", "0", "--index", str(index), "--threads", "1",
           "--describe-model", args.describe_model]
    for m in args.model:
        cmd += ["--model", m]
    (work / "cwd").mkdir()
    (work / "tmp").mkdir()
    log = work / "server.log"
    env = {**os.environ, "TMPDIR": str(work / "tmp")}
    proc = subprocess.Popen(cmd, cwd=work / "cwd", env=env, stdout=subprocess.PIPE,
                            stderr=open(log, "w"), text=True)
    assert proc.stdout is not None
    line = proc.stdout.readline()   # the server prints its address once it listens
    found = re.search(r"http://\S+/", line)
    if found is None:
        proc.kill()
        sys.exit(f"the server did not start: {line!r}; its log: {log.read_text()[-2000:]}")
    return proc, found.group(0), log


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", type=int, nargs="?", default=2000, help="requests to send")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--model", action="append", help="text-to-motion model(s) served "
                    "(default l2m-procedural: the fuzz is of the server, not of a model)")
    ap.add_argument("--describe-model", default="m2l-procedural")
    ap.add_argument("--library", type=Path, help="a folder to index (default: three "
                    "generated takes)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds a request may take")
    ap.add_argument("--check-every", type=int, default=50)
    ap.add_argument("--examples", type=int, default=5)
    args = ap.parse_args()
    args.model = args.model or ["l2m-procedural"]
    with tempfile.TemporaryDirectory(prefix="fuzz-serve-") as tmp:
        work = Path(tmp)
        library = args.library or build_library(work / "library", args.model[0])
        index = work / "library.idx"
        summary = ml.index(library, index, show_progress=False)
        print(f"index: {summary.takes} takes of {library}; server: models "
              f"{', '.join(args.model)}, describer {args.describe_model}; "
              f"{args.n} requests, seed {args.seed}", flush=True)
        t0 = time.perf_counter()
        proc, url, log = start_server(args, work, index)
        print(f"server up in {time.perf_counter() - t0:.1f} s at {url}", flush=True)
        at_start = _files(work)   # torch's own cache folder, made as a sentence encoder loads
        if at_start:
            print(f"in its TMPDIR and working folder at start: {at_start}")
        uploads = upload_seeds(DATA if DATA.is_dir() else None) + [
            [(p.name, p.read_bytes())] for p in sorted(library.rglob("*.bvh"))[:5]]
        fuzzer = Fuzzer(args.seed, uploads, args.model)
        counts: dict[str, Counter] = defaultdict(Counter)
        statuses: Counter = Counter()
        examples: dict[str, list[str]] = defaultdict(list)
        times: list[tuple[float, str]] = []
        down_checks = 0
        t0 = time.perf_counter()
        try:
            for i in range(1, args.n + 1):
                req = fuzzer.next()
                answer = send(url, req, args.timeout)
                kind = outcome(req, answer)
                counts[req.route][kind] += 1
                statuses[answer.status] += 1
                times.append((answer.seconds, f"{req.method} {req.path[:60]}"))
                fuzzer.pools.learn(req, answer)
                if kind in FAULTS and len(examples[kind]) < args.examples:
                    examples[kind].append(_example(i, req, answer))
                if i % args.check_every == 0 or kind in ("down", "hang"):
                    alive = proc.poll() is None and send(
                        url, Request("info", "GET", "/api/info"), args.timeout).status == 200
                    down_checks += not alive
                    if proc.poll() is not None:
                        print(f"the server exited ({proc.returncode}) after request {i}")
                        break
                if i % 500 == 0:
                    print(f"  {i}/{args.n} in {time.perf_counter() - t0:.0f} s", flush=True)
        finally:
            seconds = time.perf_counter() - t0
            proc.send_signal(signal.SIGINT)   # as Ctrl-C stops it
            try:
                proc.wait(60)
            except subprocess.TimeoutExpired:
                proc.kill()
        left = sorted(set(_files(work)) - set(at_start))
        traces = [ln for ln in log.read_text(errors="replace").splitlines()
                  if "Traceback" in ln or "Error" in ln][:10]
    return report(args, counts, statuses, examples, times, seconds, down_checks, left,
                  traces, proc.returncode)


def _files(work: Path) -> list[str]:
    """The files and folders in the server's working folder and TMPDIR."""
    return sorted(str(p.relative_to(work)) for d in ("cwd", "tmp") for p in (work / d).rglob("*"))


def _example(i: int, req: Request, answer) -> str:
    body = answer.body[:160].decode("utf-8", "replace").replace("\n", "\\n")
    return (f"#{i} {req.method} {req.path[:100]} ({len(req.body):,} bytes) -> "
            f"{answer.status or answer.failure}: {body}")


def report(args, counts, statuses, examples, times, seconds, down_checks, left, traces,
           returncode) -> int:
    kinds = ["ok", "refused", *FAULTS]
    print(f"\n{'route':10s}" + "".join(f"{k:>15s}" for k in kinds))
    for route in ROUTES:
        print(f"{route:10s}" + "".join(f"{counts[route][k]:15d}" for k in kinds))
    total = Counter()
    for c in counts.values():
        total.update(c)
    sent = sum(total.values())
    print(f"{'all':10s}" + "".join(f"{total[k]:15d}" for k in kinds))
    print("statuses: " + ", ".join(f"{s}: {n}" for s, n in sorted(
        statuses.items(), key=lambda kv: (kv[0] is None, kv[0] or 0))))
    secs = sorted(t for t, _ in times)
    print(f"{sent} requests in {seconds:.0f} s; answer time median "
          f"{1000 * statistics.median(secs):.0f} ms, max {secs[-1]:.1f} s; slowest: "
          + "; ".join(f"{t:.1f} s {what}" for t, what in sorted(times)[-3:]))
    for kind, lines in examples.items():
        print(f"{kind}:")
        for line in lines:
            print(f"  {line}")
    faults = sum(total[k] for k in FAULTS)
    print(f"server down at a check: {down_checks}; exit status after Ctrl-C: {returncode}; "
          f"files left in its TMPDIR and working folder (beyond those at start): {len(left)} {left[:5]}")
    if traces:
        print("the server's log:\n  " + "\n  ".join(traces))
    met = faults == 0 and down_checks == 0 and not left and sent >= args.n and \
        returncode == 0
    print(f"bar (0 faults, up throughout, no file left, >= {args.n} requests): "
          f"{'met' if met else 'NOT met'}")
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())

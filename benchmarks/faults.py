"""Faults a user meets: a full disk, a read-only one, SIGTERM and SIGINT mid-work, two runs at
once, an unusable cache, and work that exists already. How does each command end?

Runs ``motionlang`` in child processes in a temporary folder and prints one row per
scenario: exit code, stderr (one line or a traceback), temporary files left, and whether
the previous target is byte-identical (or, for a success, the output complete and
re-readable). The bar: exit 2 and one line (a signal: 128 + its number and one line), or
exit 0 with a complete output; no temporary file; every previous file intact. The
disk-full and read-only rows need a small tmpfs and so root (``mount``); they are skipped
otherwise. Exit status 1 if a row misses the bar.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/faults.py [--only WORD] [--show]
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXE = str(ROOT / ".venv" / "bin" / "motionlang")
TAG = ".motionlang-tmp."
M = "corpus/00001_mmm.xml"
TINY = ["--epochs", "1", "--offsets", "1"]


@dataclass
class Row:
    name: str
    code: int | str
    stderr: str
    temps: list[str]
    intact: bool
    ok: bool
    line: str


def digest(folder: Path) -> dict[str, str]:
    """sha256 of every file under ``folder`` (its byte-identity)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and not p.is_symlink():
            out[str(p.relative_to(folder))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def temps(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if TAG in p.name
                  or p.name.endswith(".partial"))


def stderr_kind(err: str) -> str:
    """"one line" when stderr ends with the one line that says why it stopped (progress
    lines before it are fine), else what it holds."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if "Traceback (most recent call last)" in err:
        return "traceback"
    ends = [ln for ln in lines if "error:" in ln or ln in ("terminated", "interrupted")]
    if len(ends) == 1 and lines[-1] == ends[0]:
        return "one line"
    return f"{len(lines)} lines" if lines else "nothing"


def run(args: list[str], cwd: Path, env: dict | None = None, timeout: float = 300,
        signal_after: float | None = None, sig: int = signal.SIGTERM) -> tuple[int | str, str]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MOTIONLANG_CACHE": str(cwd / ".cache"),
           **(env or {})}
    # a shell's background job inherits SIGINT ignored, and so would the command: restore it
    p = subprocess.Popen([EXE, *args], cwd=cwd, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    if signal_after is not None:
        time.sleep(signal_after)
        p.send_signal(sig)
    try:
        _, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        return "timeout", p.communicate()[1]
    return p.returncode, err


@contextlib.contextmanager
def tmpfs(folder: Path, size: str, *, fill: bool = False, readonly: bool = False,
          keep: Callable[[Path], None] | None = None) -> Iterator[Path]:
    """A tmpfs at ``folder`` (root only): ``keep`` puts files in first; then it is filled to
    the last byte or remounted read-only."""
    folder.mkdir(parents=True, exist_ok=True)
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                   check=True)
    try:
        if keep is not None:
            keep(folder)
        if fill:
            with contextlib.suppress(OSError), open(folder / "filler", "wb") as fh:
                while True:
                    fh.write(b"\0" * 4096)
                    fh.flush()
        if readonly:
            subprocess.run(["mount", "-o", "remount,ro", str(folder)], check=True)
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=False)
        shutil.rmtree(folder, ignore_errors=True)


def long_bvh(path: Path, frames: int = 6000) -> None:
    """A 5-joint chain walking for ``frames`` frames at 100 Hz (a slow render)."""
    head = ["HIERARCHY", "ROOT hips", "{", " OFFSET 0 0 0",
            " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for i in range(4):
        head += [f"JOINT j{i}", "{", " OFFSET 0 10 0", " CHANNELS 3 Zrotation Xrotation Yrotation"]
    head += ["End Site", "{", " OFFSET 0 10 0", "}"] + ["}"] * 5
    rows = [f"{t * 0.01:.3f} 90 0 {10 * (t % 50)} 0 0 " + " ".join(["5 0 0"] * 4)
            for t in range(frames)]
    path.write_text("\n".join(head + ["MOTION", f"Frames: {frames}", "Frame Time: 0.01"]
                              + rows) + "\n")


def fixtures(folder: Path) -> None:
    r = subprocess.run([EXE, "data", "synth", "--out", "corpus", "--n", "4", "--seed", "1",
                        "--workers", "1"], cwd=folder, capture_output=True, text=True)
    if r.returncode:
        sys.exit(f"cannot make the corpus: {r.stderr}")
    long_bvh(folder / "long.bvh")
    r = subprocess.run([EXE, "train", "m2l", "--data", "corpus", "--out", "done", *TINY],
                       cwd=folder, capture_output=True, text=True,
                       env={**os.environ, "OMP_NUM_THREADS": "1"})
    if r.returncode:
        sys.exit(f"cannot train the finished run: {r.stderr[-400:]}")


def outputs() -> list[tuple[str, Callable[[str], list[str]], str]]:
    """(name, arguments given an output place, what the output is: file or folder)."""
    return [
        ("convert .bvh", lambda o: ["convert", M, f"{o}/out.bvh"], "out.bvh"),
        ("render .gif", lambda o: ["render", M, f"{o}/out.gif"], "out.gif"),
        ("render .mp4", lambda o: ["render", M, f"{o}/out.mp4"], "out.mp4"),
        ("render .png strip", lambda o: ["render", M, f"{o}/out.png"], "out.png"),
        ("generate -o .bvh", lambda o: ["generate", "a person walks", "-o", f"{o}/out.bvh",
                                        "--max-frames", "20"], "out.bvh"),
        ("data synth", lambda o: ["data", "synth", "--out", f"{o}/syn", "--n", "3",
                                  "--workers", "1"], "syn"),
        ("data split", lambda o: ["data", "split", "corpus", "--out", f"{o}/split"], "split"),
        ("data export-h3d", lambda o: ["data", "export-h3d", "--data", "corpus", "--out",
                                       f"{o}/h3d"], "h3d"),
        ("train m2l", lambda o: ["train", "m2l", "--data", "corpus", "--out", f"{o}/run",
                                 *TINY], "run"),
    ]


def previous(where: Path, out: str) -> None:
    """An earlier version of the target that a failed write must leave alone."""
    if "." in out:
        (where / out).write_bytes(b"the previous version\n")


def judge(name: str, code, err: str, folder: Path, before: dict, want: int | tuple,
          after_ok: Callable[[], bool] | None = None) -> Row:
    now = digest(folder)
    intact = all(now.get(k) == v for k, v in before.items())
    left = temps(folder)
    kind = stderr_kind(err)
    wants = want if isinstance(want, tuple) else (want,)
    ok = code in wants and not left and intact and (
        kind == "one line" if code != 0 else (after_ok is None or after_ok()))
    last = err.strip().splitlines()[-1] if err.strip() else ""
    return Row(name, code, kind, left, intact, ok, last)


def disk_rows(base: Path, ro: bool) -> list[Row]:
    rows = []
    for name, args, out in outputs():
        spot = base / "spot"
        with tmpfs(spot, "256k", fill=not ro, readonly=ro,
                   keep=lambda d, out=out: previous(d, out)):
            before = digest(base)
            code, err = run(args(str(spot.relative_to(base))), base)
            rows.append(judge(f"{'read-only' if ro else 'disk full'}: {name}", code, err, base,
                              before, 2))
    return rows


def signal_rows(base: Path) -> list[Row]:
    rows = []
    work = [("render .gif (6,000 frames)", ["render", "long.bvh", "sig.gif"], "sig.gif", 4.0),
            ("render .mp4 (6,000 frames)", ["render", "long.bvh", "sig.mp4"], "sig.mp4", 4.0),
            ("data synth --n 400", ["data", "synth", "--out", "sigsyn", "--n", "400"],
             "sigsyn", 3.0),
            ("train m2l", ["train", "m2l", "--data", "corpus", "--out", "sigrun",
                           "--epochs", "50"], "sigrun", 6.0)]
    for sig, label in ((signal.SIGTERM, "SIGTERM"), (signal.SIGINT, "SIGINT")):
        for name, args, out, after in work:
            previous(base, out)
            before = digest(base)
            code, err = run(args, base, signal_after=after, sig=sig)
            rows.append(judge(f"{label} during {name}", code, err, base, before,
                              (128 + sig, 0)))
            target = base / out
            if target.is_dir():
                if label == "SIGTERM" and out == "sigrun" and (target / "last.pt").exists():
                    code, err = run(["train", "m2l", "--data", "corpus", "--out", out,
                                     "--epochs", "2", "--resume"], base)
                    rows.append(judge("  then --resume", code, err, base, {}, 0))
                shutil.rmtree(target, ignore_errors=True)
            elif target.exists():
                target.unlink()
    return rows


def readable(path: Path) -> Callable[[], bool]:
    def check() -> bool:
        r = subprocess.run([sys.executable, "-c", "import sys; from PIL import Image; "
                            "im = Image.open(sys.argv[1]); im.seek(im.n_frames - 1)",
                            str(path)], capture_output=True)
        return r.returncode == 0
    return check


def concurrent_rows(base: Path) -> list[Row]:
    rows = []
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MOTIONLANG_CACHE": str(base / ".cache")}
    for name, args, out in (("two renders of one .gif", ["render", M, "twice.gif"], "twice.gif"),
                            ("two train on one --out", ["train", "m2l", "--data", "corpus",
                                                        "--out", "both", "--epochs", "3"],
                             "both")):
        before = digest(base)
        ps = [subprocess.Popen([EXE, *args], cwd=base, env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True) for _ in range(2)]
        res = [(p.wait(timeout=600), p.communicate()[1]) for p in ps]
        codes = sorted(c for c, _ in res)
        err = next((e for c, e in res if c), "")
        ok_codes = codes in ([0, 0], [0, 2]) if out == "both" else codes == [0, 0]
        row = judge(f"concurrent: {name}", 0 if ok_codes else codes, err if codes[1] else "",
                    base, before, 0, readable(base / out) if out.endswith(".gif") else None)
        row.code = "/".join(map(str, codes))
        if out == "both" and codes != [0, 2]:   # two runs must not both write one folder
            row.ok = False
        rows.append(row)
        p = base / out
        shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink(missing_ok=True)
    return rows


def cache_rows(base: Path, root: bool) -> list[Row]:
    rows = []
    (base / "cachefile").write_text("a file where the cache folder should be\n")
    places = [("a file", str(base / "cachefile"))]
    ro = None
    if root:
        ro = tmpfs(base / "rocache", "64k", readonly=True)
        places.append(("read-only", str(ro.__enter__())))
    try:
        for what, place in places:
            before = digest(base)
            code, err = run(["train", "m2l", "--data", "corpus", "--out", "cacherun", *TINY],
                            base, env={"MOTIONLANG_CACHE": place})
            done = (base / "cacherun" / "model.pt").exists()
            row = judge(f"MOTIONLANG_CACHE {what}: train", code, "", base, before, 0,
                        lambda done=done: done)
            row.stderr = "warning" if "not used" in err else stderr_kind(err)
            rows.append(row)
            shutil.rmtree(base / "cacherun", ignore_errors=True)
    finally:
        if ro is not None:
            ro.__exit__(None, None, None)
    return rows


def existing_rows(base: Path) -> list[Row]:
    """Work that exists already must stay byte-identical (issue 44 item 0)."""
    rows = []
    cases = [("train on a finished run folder", ["train", "m2l", "--data", "corpus", "--out",
                                                 "done", *TINY]),
             ("train --resume with another seed", ["train", "m2l", "--data", "corpus", "--out",
                                                   "done", "--resume", "--seed", "7",
                                                   "--epochs", "2"]),
             ("data synth over a dataset", ["data", "synth", "--out", "corpus", "--n", "2",
                                            "--workers", "1"])]
    for name, args in cases:
        before = digest(base)
        code, err = run(args, base)
        rows.append(judge(name, code, err, base, before, 2))
    rows.append(download_over_link(base))
    return rows


def resume_rows(base: Path) -> list[Row]:
    """A training run stopped by a full disk (its run folder on a small tmpfs), its folder
    copied to a disk with room and resumed: the same model as a run that never stopped. The
    tmpfs is sized by trial, the smallest that holds the first epoch's ``last.pt``."""
    import torch
    args = ["train", "m2l", "--data", "corpus", "--offsets", "1", "--epochs", "3"]
    code, err = run([*args, "--out", "ref"], base)
    if code != 0:
        return [Row("disk full mid-train, then --resume", code, stderr_kind(err), [], True,
                    False, err.strip().splitlines()[-1] if err.strip() else "")]
    total = sum(f.stat().st_size for f in (base / "ref").rglob("*") if f.is_file())
    stopped = None
    for frac in (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9):
        spot = base / "spot"
        with tmpfs(spot, f"{int(total * frac) // 1024}k"):
            code, err = run([*args, "--out", str(spot / "run")], base)
            if code == 2 and (spot / "run" / "last.pt").is_file():
                left = temps(spot)
                shutil.copytree(spot / "run", base / "resumed")
                stopped = (code, err, left)
        if stopped:
            break
    if stopped is None:
        return [Row("disk full mid-train, then --resume", "none", "", [], True, False,
                    "no tmpfs size stopped the run after its first checkpoint")]
    code, err, left = stopped
    at = torch.load(base / "resumed" / "last.pt", map_location="cpu", weights_only=False)
    epochs_done = int(at["epoch"])    # an epoch's last.pt holds the next one's index
    rcode, rerr = run([*args, "--out", "resumed", "--resume"], base)

    def weights(run_dir: str) -> dict:
        ckpt = torch.load(base / run_dir / "model.pt", map_location="cpu", weights_only=False)
        return ckpt.get("state_dict", ckpt.get("model", ckpt))

    ref, resumed = (list(weights(d).values()) for d in ("ref", "resumed"))
    same = (rcode == 0 and len(ref) == len(resumed) > 0 and epochs_done < 3
            and all(torch.equal(a, b) for a, b in zip(ref, resumed)))
    row = judge("disk full mid-train, then --resume", code, err, base, digest(base), 2)
    row.temps, row.intact = left, same
    row.ok = row.ok and not left and same
    row.line = (f"stopped after {epochs_done} of 3 epochs; resumed elsewhere: exit {rcode}, "
                f"weights {'equal' if same else 'DIFFER'} | {row.line}")
    return [row]


def download_over_link(base: Path) -> Row:
    """``data download`` where ``DEST/<archive>.part`` is a link to a file of the user's:
    that file must stay as it is, whatever becomes of the download."""
    import zipfile
    site = base / "site"
    site.mkdir()
    with zipfile.ZipFile(site / "kit.zip", "w") as z:
        z.writestr("2017-06-22/00001_mmm.xml", "<MMM/>")
    (base / "victim.txt").write_text("a file of the user's\n")
    (base / "dl").mkdir()
    (base / "dl" / "kit.zip.part").symlink_to(base / "victim.txt")
    server = subprocess.Popen([sys.executable, "-m", "http.server", "0", "--bind",
                               "127.0.0.1"], cwd=site, stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)
    try:
        port = server.stdout.readline().split(" port ")[1].split()[0]
        before = digest(base)
        code, err = run(["data", "download", "kitml", "--dest", "dl", "--url",
                         f"http://127.0.0.1:{port}/kit.zip"], base, timeout=120)
        return judge("data download over a .part link", code, err, base, before, (0, 2))
    finally:
        server.terminate()
        server.wait()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=None, help="run only the groups whose name has this "
                    "(disk, read-only, signal, concurrent, cache, existing, resume)")
    ap.add_argument("--show", action="store_true", help="print each row's last stderr line")
    opts = ap.parse_args()
    root = hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("mount") is not None
    base = Path(tempfile.mkdtemp(prefix="motionlang-faults-"))
    groups: list[tuple[str, Callable[[], list[Row]]]] = [
        ("disk", lambda: disk_rows(base, False)), ("read-only", lambda: disk_rows(base, True)),
        ("signal", lambda: signal_rows(base)), ("concurrent", lambda: concurrent_rows(base)),
        ("cache", lambda: cache_rows(base, root)), ("existing", lambda: existing_rows(base)),
        ("resume", lambda: resume_rows(base))]
    rows: list[Row] = []
    try:
        fixtures(base)
        for name, make in groups:
            if opts.only and opts.only not in name:
                continue
            if name in ("disk", "read-only", "resume") and not root:
                print(f"({name}: skipped, needs root to mount a tmpfs)")
                continue
            t0 = time.perf_counter()
            rows += make()
            print(f"({name}: {time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    finally:
        shutil.rmtree(base, ignore_errors=True)
    print(f"{'scenario':44s} {'exit':>6s}  {'stderr':10s} {'temp':>4s}  {'intact':6s}  ok")
    for r in rows:
        print(f"{r.name[:44]:44s} {r.code!s:>6s}  {r.stderr[:10]:10s} {len(r.temps):>4d}  "
              f"{'yes' if r.intact else 'NO':6s}  {'yes' if r.ok else 'NO  <--'}")
        if opts.show or not r.ok:
            print(f"{'':46s}{r.line[:150]}")
    bad = sum(not r.ok for r in rows)
    print(f"\n{len(rows) - bad} of {len(rows)} scenarios meet the bar")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

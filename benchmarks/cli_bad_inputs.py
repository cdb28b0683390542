"""Every subcommand with bad input: how does each invocation end?

Runs ``motionlang`` in child processes (a time limit each) inside a temporary folder that
holds a small procedural corpus, a motion file, a file that is not a checkpoint and a
truncated one, and prints one row per invocation: exit code, whether stderr was one line
or a traceback, and what was left behind (new files or folders anywhere in the temporary
folder, temporary files of atomic writes). The bar: every row ends with exit 2 and one
line (or exit 0 where the input is in fact valid), and nothing is left behind. Exit status
1 if a row misses it.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/cli_bad_inputs.py [--only WORD] [--timeout S]
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXE = ROOT / ".venv" / "bin" / "motionlang"
BIG = str(2**70)

# bad places for an output file (ext added) and for an output folder
BAD_FILES = {"under /sys": "/sys/motionlang-x{ext}", "existing folder": "adir",
             "under a file": "afile/x{ext}", "empty": ""}
BAD_DIRS = {"under /sys": "/sys/motionlang-x", "existing file": "afile",
            "under a file": "afile/x", "empty": ""}


def cases() -> list[tuple[str, list[str], int]]:
    """(name, arguments, expected exit code) rows."""
    m = "corpus/00001_mmm.xml"
    rows: list[tuple[str, list[str], int]] = []
    for where, path in BAD_FILES.items():
        def f(ext: str, path: str = path) -> str:
            return path.format(ext=ext)
        rows += [(f"render OUT {where}", ["render", m, f(".gif")], 2),
                 (f"convert OUT {where}", ["convert", m, f(".bvh")], 2),
                 (f"generate -o {where}", ["generate", "a person walks", "-o", f(".gif")], 2),
                 (f"evaluate -o {where}", ["evaluate", "--m2l", "junk.pt", "--data", "corpus",
                                           "-o", f(".json")], 2)]
    for where, path in BAD_DIRS.items():
        rows += [(f"train twostream --out {where}", ["train", "twostream", "--data", "corpus",
                                                     "--out", path], 2),
                 (f"train crbm --out {where}", ["train", "crbm", "--data", "corpus",
                                                "--out", path], 2)]
        rows += [(f"demo --out {where}", ["demo", "--out", path], 2),
                 (f"data synth --out {where}", ["data", "synth", "--out", path, "--n", "1"], 2),
                 (f"data split --out {where}", ["data", "split", "corpus",
                                                "--out", path], 2),
                 (f"data export-h3d --out {where}", ["data", "export-h3d", "--data", "corpus",
                                                     "--out", path], 2),
                 (f"train m2l --out {where}", ["train", "m2l", "--data", "corpus",
                                               "--out", path], 2),
                 (f"train l2m --out {where}", ["train", "l2m", "--data", "corpus",
                                               "--out", path], 2)]
    for opt in ("--start", "--end"):
        for v in ("nan", "inf", "-inf"):
            rows.append((f"render {opt} {v}", ["render", m, "o.gif", opt, v], 2))
            rows.append((f"convert {opt} {v}", ["convert", m, "o.bvh", opt, v], 2))
    rows += [
        ("render --fps inf", ["render", m, "o.gif", "--fps", "inf"], 2),
        ("render --fps 0", ["render", m, "o.gif", "--fps", "0"], 2),
        ("render --strip 0", ["render", m, "o.png", "--strip", "0"], 2),
        ("data split --fractions nan", ["data", "split", "corpus", "--out", "s",
                                        "--fractions", "nan", "0.1", "0.1"], 2),
        ("data split --fractions inf", ["data", "split", "corpus", "--out", "s",
                                        "--fractions", "inf", "0.1", "0.1"], 2),
        ("data split --seed -1", ["data", "split", "corpus", "--out", "s",
                                  "--seed", "-1"], 2),
        ("data split --seed 2**70", ["data", "split", "corpus", "--out", "s",
                                     "--seed", BIG], 2),
        ("data synth --n 0", ["data", "synth", "--out", "syn", "--n", "0"], 2),
        ("data synth --seed -1", ["data", "synth", "--out", "syn", "--n", "1", "--seed", "-1"], 2),
        ("describe -w 0", ["describe", m, "-w", "0"], 2),
        ("describe -w -1", ["describe", m, "-w", "-1"], 2),
        ("describe -w 1000000", ["describe", m, "-w", "1000000"], 2),
        ("describe --length-penalty nan", ["describe", m, "--length-penalty", "nan"], 2),
        ("describe --model not a checkpoint", ["describe", m, "--model", "junk.pt"], 2),
        ("describe --model truncated", ["describe", m, "--model", "truncated.pt"], 2),
        ("generate ''", ["generate", "", "-o", "g.gif"], 2),
        ("generate '!!!'", ["generate", "!!!", "-o", "g.gif"], 2),
        ("generate --seed -1", ["generate", "a person walks", "-o", "g.gif", "--seed", "-1"], 2),
        ("generate --seed 2**70", ["generate", "a person walks", "-o", "g.gif", "--seed", BIG], 2),
        ("generate -w 0", ["generate", "a person walks", "-o", "g.gif", "-w", "0"], 2),
        ("generate --max-frames -5", ["generate", "a person walks", "-o", "g.gif",
                                      "--max-frames", "-5"], 2),
        ("generate --temperature inf", ["generate", "a person walks", "-o", "g.gif",
                                        "--temperature", "inf"], 2),
        ("generate --model not a checkpoint", ["generate", "a person walks", "-o", "g.gif",
                                               "--model", "junk.pt"], 2),
        ("demo --seed -1", ["demo", "--out", "d", "--seed", "-1"], 2),
        ("demo -w 0", ["demo", "--out", "d", "-w", "0"], 2),
        ("demo --max-frames -5", ["demo", "--out", "d", "--max-frames", "-5"], 2),
        ("evaluate -w 0", ["evaluate", "--m2l", "junk.pt", "--data", "corpus", "-w", "0"], 2),
        ("evaluate --m2l not a checkpoint", ["evaluate", "--m2l", "junk.pt", "--data",
                                             "corpus"], 2),
    ]
    # a model's sampling options (--model NAME:key=value): unknown, mistyped, contradictory
    for spec in ("l2m:beam=3", "l2m:width=two", "l2m:method=mean,rerank=m2l", "l2m:width=0",
                 "l2m:method=sample,width", "junk.pt:method=sample", "twostream:width=2"):
        rows += [(f"evaluate-t2m --model {spec}", ["evaluate-t2m", "--data", "corpus",
                                                  "--model", spec, "-o", "t2m"], 2),
                 (f"evaluate --t2m {spec}", ["evaluate", "--m2l", "m2l", "--data", "corpus",
                                             "--t2m", spec, "-o", "r.json"], 2)]
    m2l = ["train", "m2l", "--data", "corpus", "--out", "run"]
    rows += [(f"train m2l {' '.join(o)}", m2l + o, 2) for o in (
        ["--batch-size", "0"], ["--batch-size", "-1"], ["--lr", "nan"], ["--lr", "inf"],
        ["--enc-hidden", "0"], ["--dropout", "2"], ["--dropout", "nan"], ["--seed", "-1"],
        ["--seed", BIG], ["--epochs", "-1"], ["--resume"])]
    rows.append(("train m2l --resume, last.pt truncated",
                 ["train", "m2l", "--data", "corpus", "--out", "oldrun", "--resume"], 2))
    l2m = ["train", "l2m", "--data", "corpus", "--out", "run"]
    rows += [(f"train l2m {' '.join(o)}", l2m + o, 2) for o in (
        ["--components", "0"], ["--lr", "nan"], ["--rollout", "2"], ["--resume"])]
    ts = ["train", "twostream", "--data", "corpus", "--out", "ts"]
    rows += [(f"train twostream {' '.join(o)}", ts + o, 2) for o in (
        ["--h", "0"], ["--lr", "nan"], ["--batch-size", "0"], ["--seed", "-1"], ["--resume"])]
    crbm = ["train", "crbm", "--data", "corpus", "--out", "crbm"]
    rows += [(f"train crbm {' '.join(o)}", crbm + o, 2) for o in (
        ["--order", "1000000"], ["--lr", "nan"], ["--hidden", "0"], ["--batch-size", "0"],
        ["--momentum", "inf"], ["--seed", "-1"])]
    rows += [
        ("crbm generate --frames -5", ["crbm", "generate", "junk.pt", "g.npy", "--frames", "-5"], 2),
        ("crbm generate OUT existing folder", ["crbm", "generate", "junk.pt", "adir"], 2),
        ("crbm fill --repeats 0", ["crbm", "fill", "junk.pt", "f.npy", "--repeats", "0"], 2),
    ]
    ix = ["index", "corpus", "-o", "l.idx", "--model", "twostream"]
    rows += [(f"index -o {where}", ix[:2] + ["-o", path.format(ext=".idx")] + ix[4:], 2)
             for where, path in BAD_FILES.items()]
    rows += [(f"search --render {where}", ["search", "walks", "--index", "junk.pt",
                                           "--render", path.format(ext=".png")], 2)
             for where, path in BAD_FILES.items()]
    rows += [(f"index {' '.join(o)}", ix + o, 2) for o in (
        ["--window", "0"], ["--window", "inf"], ["--hop", "nan"], ["--hop", "5"])]
    rows += [
        ("index DIR missing", ["index", "nodir", "-o", "l.idx", "--model", "twostream"], 2),
        ("index --model not a checkpoint", ix[:4] + ["--model", "junk.pt"], 2),
        ("index --model m2l (motions only)", ix[:4] + ["--model", "m2l"], 2),
        ("index -o a file that is not an index", ix[:2] + ["-o", "afile"] + ix[4:], 2),
        ("search --index not an index", ["search", "walks", "--index", "junk.pt"], 2),
        ("search --index missing", ["search", "walks", "--index", "none.idx"], 2),
        ("search -k 0", ["search", "walks", "--index", "junk.pt", "-k", "0"], 2),
        ("search --render .gif", ["search", "walks", "--index", "junk.pt", "--render",
                                  "x.gif"], 2),
    ]
    dd = ["describe", "corpus", "-o", "d.jsonl"]
    rows += [(f"describe DIR -o {where}", dd[:3] + [path.format(ext=".jsonl")], 2)
             for where, path in BAD_FILES.items()]
    rows += [(f"describe DIR {' '.join(o)}", dd + o, 2) for o in (
        ["--segments", "--window", "0"], ["--segments", "--hop", "nan"],
        ["--segments", "--hop", "5"], ["--bridge", "-1"], ["--workers", "0"],
        ["--bank", "none.txt"], ["--bank", "afile", "--model", "m2l"],
        ["--model", "junk.pt"])]
    rows.append(("describe DIR missing", ["describe", "nodir", "-o", "d.jsonl"], 2))
    return rows + audit_cases(m)


def audit_cases(m: str) -> list[tuple[str, list[str], int]]:
    """The second audit's classes (issue 44): numbers beyond any use, absurd sizes and
    counts, contradictory options, frame times of a day, deep rigs, bad download folders."""
    rows: list[tuple[str, list[str], int]] = []
    m2l = ["train", "m2l", "--data", "corpus", "--out", "run"]
    for v in ("1e308", "1e-300"):
        rows += [(f"train m2l --lr {v}", m2l + ["--lr", v], 2),
                 (f"describe --length-penalty {v}", ["describe", m, "--length-penalty", v], 2),
                 (f"render --source-fps {v}", ["render", m, "o.gif", "--source-fps", v], 2),
                 (f"render --fps {v}", ["render", m, "o.gif", "--fps", v], 2),
                 (f"convert --end {v}", ["convert", m, "o.bvh", "--end", v], 2)]
    rows += [
        ("data synth --n 10**12", ["data", "synth", "--out", "syn", "--n", str(10**12)], 2),
        ("data synth --workers 10000 (capped)", ["data", "synth", "--out", "syn", "--n", "2",
                                                 "--workers", "10000"], 0),
        ("crbm fill --gibbs 10**9", ["crbm", "fill", "junk.pt", "f.npy", "--gibbs",
                                     str(10**9)], 2),
        ("render --strip 10**6", ["render", m, "o.png", "--strip", str(10**6)], 2),
        ("train m2l --offsets 10**9", m2l + ["--offsets", str(10**9)], 2),
        ("train m2l --min-count 10**9", m2l + ["--min-count", str(10**9)], 2),
        ("train m2l --data bandai:", ["train", "m2l", "--data", "bandai:", "--out", "run"], 2),
        ("generate --min-frames > --max-frames", ["generate", "a person walks", "-o",
                                                  "g.bvh", "--min-frames", "50",
                                                  "--max-frames", "10"], 2),
        ("train l2m --plan-weight, no --plan-parts", ["train", "l2m", "--data", "corpus",
                                                      "--out", "run", "--plan-weight", "2"], 2),
        ("render BVH Frame Time 1e5 (200,001 frames)", ["render", "slow.bvh", "o.gif"], 2),
        ("describe BVH Frame Time 1e9", ["describe", "slow9.bvh"], 2),
        ("convert 1,990-joint chain", ["convert", "deep.bvh", "o.bvh"], 0),
    ]
    rows += [(f"data download --dest {what}", ["data", "download", "kitml", "--dest", d], 2)
             for what, d in (("a file", "afile"), ("under /proc", "/proc/motionlang-x"),
                             ("under /sys", "/sys/motionlang-x"), ("''", ""))]
    return rows


def bvh(frame_time: str, joints: int = 1, frames: int = 3) -> str:
    """A chain of ``joints`` joints (one channel set each) for ``frames`` frames."""
    lines = ["HIERARCHY", "ROOT j0", "{", " OFFSET 0 0 0",
             " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for i in range(1, joints):
        lines += [f"JOINT j{i}", "{", " OFFSET 0 1 0", " CHANNELS 3 Zrotation Xrotation "
                  "Yrotation"]
    lines += ["End Site", "{", " OFFSET 0 1 0", "}"] + ["}"] * joints
    row = " ".join(["0"] * (6 + 3 * (joints - 1)))
    return "\n".join(lines + ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time}"]
                     + [row] * frames) + "\n"


def snapshot(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def make_fixtures(folder: Path, timeout: float) -> set[str]:
    """The corpus, files and folders the cases point at; returns the folder's listing."""
    subprocess.run([str(EXE), "data", "synth", "--out", "corpus", "--n", "4", "--seed", "1",
                    "--workers", "1"], cwd=folder, check=True, timeout=timeout,
                   capture_output=True)
    (folder / "adir").mkdir()
    (folder / "afile").write_text("a file, not a folder\n")
    (folder / "junk.pt").write_text("not a checkpoint\n")
    (folder / "slow.bvh").write_text(bvh("100000"))
    (folder / "slow9.bvh").write_text(bvh("1e9", joints=30))
    (folder / "deep.bvh").write_text(bvh("0.01", joints=1990, frames=2))
    packaged = ROOT / "src" / "motionlang" / "data" / "models" / "m2l.pt"
    cut = packaged.read_bytes()[:4096] if packaged.exists() else b"PK\x03\x04" + b"\0" * 64
    (folder / "truncated.pt").write_bytes(cut)
    (folder / "oldrun").mkdir()
    (folder / "oldrun" / "last.pt").write_bytes(cut)
    return snapshot(folder)


def run_case(args: list[str], folder: Path, timeout: float) -> tuple[int | str, str, float]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MOTIONLANG_CACHE": str(folder / ".cache")}
    t0 = time.perf_counter()
    try:
        r = subprocess.run([str(EXE), *args], cwd=folder, env=env, capture_output=True,
                           text=True, timeout=timeout)
        return r.returncode, r.stderr, time.perf_counter() - t0
    except subprocess.TimeoutExpired as exc:
        err = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) else ""
        return "timeout", err or "", time.perf_counter() - t0


def describe_stderr(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if "Traceback (most recent call last)" in err:
        return "traceback: " + (lines[-1][:70] if lines else "")
    if len(lines) == 1:
        return "one line"
    return f"{len(lines)} lines" if lines else "no message"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=None, help="run only rows whose name contains this")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per invocation")
    ap.add_argument("--show", action="store_true", help="print each row's stderr line")
    opts = ap.parse_args()
    rows = [r for r in cases() if opts.only is None or opts.only in r[0]]
    folder = Path(tempfile.mkdtemp(prefix="motionlang-cli-bad-"))
    failures = 0
    try:
        base = make_fixtures(folder, opts.timeout)
        base |= {".cache"}
        print(f"{'invocation':46s} {'exit':>7s}  {'stderr':22s} {'s':>5s}  left behind")
        for name, args, want in rows:
            code, err, secs = run_case(args, folder, opts.timeout)
            now = snapshot(folder)
            new = sorted(p for p in now - base if not p.startswith(".cache"))
            outcome = describe_stderr(err)
            # a valid input writes its output; only temporary files count then
            stray = [p for p in new if ".motionlang-tmp." in p] if want == 0 else new
            ok = code == want and (outcome == "one line" or want == 0) and not stray
            failures += not ok
            print(f"{name[:46]:46s} {code!s:>7s}  {outcome[:22]:22s} {secs:5.1f}  "
                  f"{', '.join(new)[:60] or '-'}{'' if ok else '   <-- FAIL'}")
            if opts.show or not ok:
                shown = err.strip().splitlines()[-1] if err.strip() else ""
                print(f"{'':48s}{shown[:150]}")
            for p in new:   # each row starts from the same folder
                path = folder / p
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path, ignore_errors=True)
                elif path.exists():
                    path.unlink()
            stray = [p for p in Path("/sys").glob("motionlang-x*")]
            if stray:
                print(f"{'':48s}left under /sys: {stray}")
                failures += 1
        print(f"\n{len(rows) - failures} of {len(rows)} rows meet the bar "
              "(exit 2 and one line, or exit 0 for valid input; nothing left behind)")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

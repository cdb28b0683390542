"""What the grounded analysis (``motionlang.analysis``) says of real takes: one line per file
with its main action, sentence and timing, for the development folders (``cmu_dev``, CMU 49,
DeepMimic clips, Bandai archives).

    .venv/bin/python experiments/analysis_cmu_dev.py FILE_OR_DIR ... [--trials trials.tsv]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--trials", default=None, help="cmu_dev's trials.tsv (adds CMU's words)")
    ap.add_argument("--detail", action="store_true")
    args = ap.parse_args()
    from motionlang.analysis import analyse
    from motionlang.formats import read_motion
    labels = {}
    if args.trials:
        for line in Path(args.trials).read_text().splitlines()[1:]:
            cols = line.split("\t")
            labels[cols[1]] = cols[5]
    files = []
    for p in map(Path, args.paths):
        files += sorted(q for q in p.rglob("*") if q.suffix.lower() in (".bvh", ".amc", ".txt",
                                                                       ".xml")) \
            if p.is_dir() else [p]
    for f in files:
        try:
            m = read_motion(f)
            t = time.perf_counter()
            a = analyse(m)
            dt = time.perf_counter() - t
        except Exception as exc:   # noqa: BLE001 - a survey goes on past one bad file
            print(f"{f.name}\tERROR {type(exc).__name__}: {exc}")
            continue
        key = "/".join(f.parts[-2:])
        print(f"{key}\t{labels.get(key, '')}\t{a.main_action()}\t{a.sentence()}\t"
              f"{m.n_frames / m.fps:.1f}s\t{dt * 1000:.0f}ms", flush=True)
        if args.detail:
            for x in a.findings:
                print("      ", x.evidence())


if __name__ == "__main__":
    main()

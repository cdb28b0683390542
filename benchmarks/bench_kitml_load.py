"""Time ``load_kitml`` on a synthetic release of N copies of the real motion 00001.

Prints medians of repeated runs: the whole load, and the frame count of one MMM file done
cheaply (head/tail time stamps) versus exactly (scan of every byte).

    .venv/bin/python benchmarks/bench_kitml_load.py [N]
"""
from __future__ import annotations

import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

from motionlang.datasets.kitml import count_mmm_frames, load_kitml

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "kitml" / "00001_mmm.xml"


def median_time(fn, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> int:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 300
    if not SHARED.exists():
        print(f"skipped: {SHARED} not present")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for i in range(1, n + 1):
            shutil.copy(SHARED, root / f"{i:05d}_mmm.xml")
            (root / f"{i:05d}_annotations.json").write_text('["A person walks forward."]')
            (root / f"{i:05d}_meta.json").write_text("{}")
        t_load = median_time(lambda: load_kitml(root))
        t_cheap = median_time(lambda: count_mmm_frames(SHARED), 20)
        t_exact = median_time(lambda: count_mmm_frames(SHARED, window=1 << 30), 20)
    print(f"load_kitml, {n} motions: median {t_load * 1e3:.1f} ms "
          f"({t_load / n * 1e6:.0f} us per motion)")
    print(f"frame count of one 344 kB MMM file: cheap {t_cheap * 1e6:.0f} us, "
          f"exact {t_exact * 1e6:.0f} us (median)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

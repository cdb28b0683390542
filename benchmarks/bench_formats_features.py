"""Reading, feature extraction and rendering speed on the real files (median of repeated runs).

Run: .venv/bin/python benchmarks/bench_formats_features.py
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import median_time, need_data  # noqa: E402

from motionlang.features import AnglesFeatures, PositionFeatures, TaylorFeatures  # noqa: E402
from motionlang.formats.asf_amc import read_asf_amc  # noqa: E402
from motionlang.formats.mmm import read_mmm, write_mmm  # noqa: E402
from motionlang.rendering.animation import render_animation
from motionlang.rendering.strip import render_strip  # noqa: E402


def main() -> None:
    mmm_path = need_data("kitml/00001_mmm.xml")
    asf, amc = need_data("cmu35/35.asf"), need_data("cmu35/35_01.amc")
    m = read_mmm(mmm_path)
    c = read_asf_amc(asf, amc)
    a, p, t = AnglesFeatures().fit([m]), PositionFeatures().fit([m]), TaylorFeatures().fit([c])
    out = Path(tempfile.mkdtemp())
    rows = [
        ("read_mmm 00001 (378 frames)", lambda: read_mmm(mmm_path), 7),
        ("write_mmm 00001 (378 frames)", lambda: write_mmm(m, out / "w_mmm.xml"), 7),
        ("read_asf_amc 35_01 (358 frames)", lambda: read_asf_amc(asf, amc), 7),
        ("forward kinematics 00001", lambda: m.positions(), 7),
        ("angles.encode_all 00001 (10 sequences)", lambda: a.encode_all(m), 7),
        ("positions.encode 00001", lambda: p.encode(m), 7),
        ("taylor.encode 35_01", lambda: t.encode(c), 7),
        ("taylor.decode 35_01", lambda: t.decode(t.encode(c)), 7),
        ("render_strip 00001 (8 poses)", lambda: render_strip(m, out / "s.png"), 3),
        ("render_animation 00001 -> GIF", lambda: render_animation(m, out / "a.gif"), 3),
    ]
    for name, fn, repeat in rows:
        print(f"{name:45s} median {median_time(fn, repeat=repeat) * 1e3:9.1f} ms  ({repeat} runs)")


if __name__ == "__main__":
    main()

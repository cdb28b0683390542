"""Reading a 10-minute 120 Hz BVH (72,000 frames) of a 31-joint CMU-style rig, on one core.

The bar (GitHub issue, item 1): reading, and reading plus mapping to the 21 body joints
(``features.joint_map.positions21``), each under 5 s. The file is built in a temporary
folder: CMU BVH joint names (cgspeed's conversion), centimetres, 96 channels, smooth random
angles (a few sines per channel) and a walk round a 5 m circle. Prints the medians of 3
runs and the reader's peak memory (tracemalloc, a separate untimed run).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_bvh_read.py [minutes]
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")   # one core, set before numpy loads its BLAS

import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import median_time  # noqa: E402

from motionlang.errors import MotionlangError  # noqa: E402
from motionlang.formats.bvh import read_bvh  # noqa: E402

FPS = 120
BAR_S = 5.0
ROT = "CHANNELS 3 Zrotation Xrotation Yrotation"


def _side(s: str, x: float) -> dict:
    """Leg and arm chains of one side (``s`` = "Left"/"Right", ``x`` = +1/-1), cm."""
    L = s[0]
    leg = (f"{L}HipJoint", (0, 0, 0), [(f"{s}UpLeg", (9 * x, -6, 2), [(f"{s}Leg", (0, -43, 0), [
        (f"{s}Foot", (0, -42, 0), [(f"{s}ToeBase", (0, -6, 13), [(None, (0, 0, 5), [])])])])])])
    hand = [(f"{s}FingerBase", (3 * x, 0, 0), [(f"{s}HandIndex1", (4 * x, 0, 0),
                                                  [(None, (3 * x, 0, 0), [])])]),
            (f"{L}Thumb", (2 * x, 0, 2), [(None, (3 * x, 0, 0), [])])]
    arm = (f"{s}Shoulder", (3 * x, 9, 0), [(f"{s}Arm", (15 * x, 0, 0), [
        (f"{s}ForeArm", (28 * x, 0, 0), [(f"{s}Hand", (25 * x, 0, 0), hand)])])])
    return {"leg": leg, "arm": arm}


def _rig():
    left, right = _side("Left", 1), _side("Right", -1)
    head = ("Neck", (0, 12, 0), [("Neck1", (0, 5, 0), [("Head", (0, 5, 1),
                                                         [(None, (0, 15, 0), [])])])])
    spine = ("LowerBack", (0, 0, 0), [("Spine", (0, 11, -1), [
        ("Spine1", (0, 11, 0), [head, left["arm"], right["arm"]])])])
    return ("Hips", (0, 0, 0), [left["leg"], right["leg"], spine])


def _header(root) -> tuple[str, int]:
    """HIERARCHY text and the number of joints with channels."""
    out, count = ["HIERARCHY"], [0]

    def emit(node, depth):
        name, offset, kids = node
        ind = "\t" * depth
        off = " ".join(f"{v:g}" for v in offset)
        if name is None:
            out.extend([f"{ind}End Site", ind + "{", f"{ind}\tOFFSET {off}", ind + "}"])
            return
        count[0] += 1
        chans = ("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
                 if depth == 0 else ROT)
        out.extend([f"{ind}{'ROOT' if depth == 0 else 'JOINT'} {name}", ind + "{",
                    f"{ind}\tOFFSET {off}", f"{ind}\t{chans}"])
        for k in kids:
            emit(k, depth + 1)
        out.append(ind + "}")

    emit(root, 0)
    return "\n".join(out) + "\n", count[0]


def build(path: Path, minutes: float) -> tuple[int, int]:
    """Write the benchmark file; returns (frames, channels)."""
    header, joints = _header(_rig())
    T, C = int(minutes * 60 * FPS), 6 + 3 * (joints - 1)
    rng = np.random.default_rng(0)
    t = np.arange(T) / FPS
    data = np.zeros((T, C))
    for _ in range(3):   # smooth angles: sines of 0.2-2 Hz, 5-15 degrees each
        f, a, ph = rng.uniform(0.2, 2, C), rng.uniform(5, 15, C), rng.uniform(0, 2 * np.pi, C)
        data += a * np.sin(2 * np.pi * f * t[:, None] + ph)
    omega = 1.2 / 5.0                     # rad/s: 1.2 m/s round a 5 m (500 cm) circle
    data[:, 0], data[:, 2] = 500 * np.cos(omega * t), 500 * np.sin(omega * t)
    data[:, 1] = 95 + 2 * np.sin(2 * np.pi * 2 * t)
    with open(path, "w") as fh:
        fh.write(header)
        fh.write(f"MOTION\nFrames: {T}\nFrame Time: {1 / FPS:.7f}\n")
        np.savetxt(fh, data, fmt="%.6f")
    return T, C


def main() -> int:
    minutes = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "long.bvh"
        t0 = time.perf_counter()
        T, C = build(path, minutes)
        size = path.stat().st_size / 1e6
        print(f"built {path.name}: {T} frames x {C} channels at {FPS} Hz "
              f"({minutes:g} min), {size:.0f} MB, in {time.perf_counter() - t0:.1f} s")
        m = read_bvh(path)
        print(f"read: {len(m.skeleton)} nodes, {m.fps:g} fps, unit {m.meta['unit']}, "
              f"stature {m.meta['stature_m']:.2f} m")
        t_read = median_time(lambda: read_bvh(path), repeat=3)
        print(f"read_bvh                      median {t_read:6.2f} s  (bar {BAR_S:g} s: "
              f"{'ok' if t_read < BAR_S else 'TOO SLOW'})")
        try:
            from motionlang.features.joint_map import positions21
            positions21(m[:10])
        except (ImportError, MotionlangError) as exc:
            print(f"read_bvh + positions21        skipped: {exc}")
        else:
            t_map = median_time(lambda: positions21(read_bvh(path)), repeat=3)
            print(f"read_bvh + positions21        median {t_map:6.2f} s  (bar {BAR_S:g} s: "
                  f"{'ok' if t_map < BAR_S else 'TOO SLOW'})")
        del m
        tracemalloc.start()
        read_bvh(path)
        peak = tracemalloc.get_traced_memory()[1] / 1e6
        tracemalloc.stop()
        print(f"read_bvh peak traced memory   {peak:6.0f} MB  (file {size:.0f} MB, its "
              f"(T, C) float64 values {T * C * 8 / 1e6:.0f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

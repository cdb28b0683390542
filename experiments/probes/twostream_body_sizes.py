"""How much of the sources' unlike spread is body size? For each source of the two-stream
package's data (the procedural corpus, the Bandai takes), over its training motions: the
body's size (the median over frames of the left leg's and the spine's bone lengths: hip to
knee to ankle, root to neck to head; metres, the same whatever the pose), and the spread of
the joints' heights in the body frame (the median over the 21 joints of their standard
deviation), in metres and relative to each motion's size.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_body_sizes.py \\
        --corpus runs/twostream_parts/corpus [--bandai ../shared/data/bandai]

If the spreads relative to body size are close, joints measured against the body's size
would let one normaliser weigh both sources alike (``docs/results/twostream.md``, "A
normaliser per source").
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--corpus", required=True)
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    a = ap.parse_args()
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.features.joint_map import KIT21_NAMES
    from motionlang.features.positions import local_joints

    data = build_twostream_data([a.corpus, f"bandai:{a.bandai}"])
    norm, at = data.features.normalizer, {n: i for i, n in enumerate(KIT21_NAMES)}

    def bone(j: np.ndarray, u: str, v: str) -> np.ndarray:
        return np.linalg.norm(j[:, at[u]] - j[:, at[v]], axis=-1)

    chain = (("LH", "LK"), ("LK", "LA"), ("root", "BT"), ("BT", "BLN"), ("BLN", "BUN"))
    for s, name in enumerate((a.corpus, "bandai")):
        joints = [local_joints(norm.inverse(data.sequences[i].astype(np.float64)))
                  for i in data.splits["train"] if data.sources[i] == s]
        size = np.array([np.median(sum(bone(j, u, v) for u, v in chain)) for j in joints])
        heights = np.concatenate([j[..., 1] for j in joints])
        relative = np.concatenate([j[..., 1] / z for j, z in zip(joints, size)])
        print(f"{name}: {len(joints)} motions; body size {np.median(size):.3f} m (spread "
              f"{size.std():.3f}); joints' heights spread {np.median(heights.std(0)):.4f} m, "
              f"relative to the size {np.median(relative.std(0)):.4f} "
              f"(= {np.median(relative.std(0)) * np.median(size):.4f} m at the median size)")


if __name__ == "__main__":
    main()

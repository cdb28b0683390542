"""The foot lock and the root measures on real rigs and real takes (docs/results/real-motion.md,
fourth session): the figures quoted there beside the judge table.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/foot_lock_checks.py [--model l2m]
        [--data ../shared/data/bandai] [--out /tmp/foot_lock_checks]

1. "a person walks forward" generated as ``motionlang generate`` writes it, with and without
   the lock, as .npz, as .bvh on the 21-joint body and as .bvh retargeted onto a Bandai rig
   (dataset-1_walk_normal_001.bvh from the archives); each file read back and its foot
   skating measured on its 21-joint body (``features.body21``). Also the highest the decoded
   toes rise.
2. On the Bandai test takes: how many real takes, and how many of the model's motions for
   their sentences, move the root more than 10 cm in one frame (12.5 Hz), and the contents
   of the latter.
Non-commercial: the Bandai data and the packaged models trained on it are CC BY-NC 4.0.
"""
from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", default="l2m")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--out", default="/tmp/foot_lock_checks")
    args = p.parse_args()

    import numpy as np
    import torch
    torch.set_num_threads(1)
    from motionlang.cli.main import main as cli
    from motionlang.datasets.bandai import bandai_folders
    from motionlang.decoding.t2m import FPS, text_to_motion
    from motionlang.evaluation.metrics.physics import foot_skating, root_jitter
    from motionlang.features.body21 import body21
    from motionlang.formats import read_motion
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.registry import load_model
    from motionlang.utils.progress import progress

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rig = next(f for d in bandai_folders(args.data)
               for f in (d / "data").glob("dataset-1_walk_normal_001.bvh"))
    text = "a person walks forward"
    for lock in (True, False):
        tag = "" if lock else "_raw"
        flag = [] if lock else ["--no-foot-lock"]
        for name, extra in ((f"walk{tag}.npz", []), (f"walk{tag}.bvh", []),
                            (f"walk{tag}_rig.bvh", ["--rig", str(rig)])):
            assert cli(["generate", text, "--model", args.model, "-w", "1", "-o",
                        str(out / name)] + flag + extra) == 0
            if name.endswith(".npz"):
                pos, fps = np.load(out / name)["positions"], 12.5
            else:
                m = read_motion(out / name)
                pos, fps = body21(m), m.fps
            print(f"{name}: foot skating {foot_skating(pos, fps):.3f} m/s"
                  + ("" if lock or not name.endswith(".npz") else
                     f", toes at most {pos[:, [15, 20], 1].max() * 100:.1f} cm up"))

    t2m = text_to_motion(load_model(args.model))
    real = bandai_items(args.data, "test", fps=FPS)
    sentences = bandai_sentences(args.data, "test")
    jumps_real = [root_jitter(it.positions) for it in real]
    jumps_gen = [root_jitter(t2m.positions21(s.text, max(2, len(it.positions))))
                 for s, it in progress(list(zip(sentences, real)), desc="generate",
                                       unit="motions")]
    over = [s.content for s, j in zip(sentences, jumps_gen) if j > 0.10]
    print(f"{len(real)} Bandai test takes: root moves over 10 cm in one frame in "
          f"{sum(j > 0.10 for j in jumps_real)} real takes, in {len(over)} of {args.model}'s "
          f"motions (contents: {', '.join(sorted(set(over)))})")


if __name__ == "__main__":
    main()

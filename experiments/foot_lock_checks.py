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
    import motionlang as ml
    from motionlang.api import generate_hypotheses, load_rig, write_result
    from motionlang.datasets.bandai import bandai_folders
    from motionlang.evaluation.metrics.physics import foot_skating, root_jitter
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.t2m import FPS
    from motionlang.utils.progress import progress

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rig = next(f for d in bandai_folders(args.data)
               for f in (d / "data").glob("dataset-1_walk_normal_001.bvh"))
    text = "a person walks forward"
    for lock in (True, False):
        tag = "" if lock else "_raw"
        for name, on_rig in ((f"walk{tag}.npz", None), (f"walk{tag}.bvh", None),
                             (f"walk{tag}_rig.bvh", load_rig(rig))):
            # as `motionlang generate TEXT --model M -w 1 -o NAME [--no-foot-lock] [--rig R]`
            # writes it, and its line
            hyps, fps = generate_hypotheses(text, args.model, width=1, foot_lock=lock)
            result, score = hyps[0]
            note = write_result(result, out / name, fps=fps, title=f"{text} (#1)", rig=on_rig)
            n = len(result.joint_angles) if hasattr(result, "joint_angles") else len(result)
            likelihood = "" if np.isnan(score) else f" log L = {score:10.2f} "
            print(f"1.{likelihood} {n} frames  -> {out / name}{note}")
            if name.endswith(".npz"):
                pos, fps = np.load(out / name)["positions"], 12.5
            else:
                m = ml.read_motion(out / name)
                pos, fps = ml.body21(m), m.fps
            print(f"{name}: foot skating {foot_skating(pos, fps):.3f} m/s"
                  + ("" if lock or not name.endswith(".npz") else
                     f", toes at most {pos[:, [15, 20], 1].max() * 100:.1f} cm up"))

    t2m = ml.text_to_motion(args.model)
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

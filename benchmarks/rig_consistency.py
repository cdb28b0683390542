"""Does the same motion get the same first action on every rig? (issue 41, item 4; issue
57's rig copies)

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/rig_consistency.py [--model m2l]
        [--data ../shared/data] [--cmudev /tmp/cmudev] [--seconds 10] [--every 1]
        [--compare action] [--deepmimic DIR] [--rate HZ]

Sources: the first copy of every ``cmu_dev`` trial (extracted from
``cmu_dev/cmu-dev.tar.xz`` to ``--cmudev`` if absent), CMU 35's trials
(``cmu35WalkJog.mat``, read as AMC channels on the ASF skeleton) and ten Bandai Namco test
takes of dataset 2 (walk, run, waves, raises), each cut to its first ``--seconds``. Each is
described as read, then retargeted onto four real rigs people share motion in (a Bandai take,
and ``cmu_dev``'s iClone CC, Second-Life and 164-joint MakeHuman files), written as BVH, read
back and described again. Printed: for each rig, the share of sources whose first sentence
names the same gait (walk / run / jump, or none) as the original's, and each disagreement;
with ``--compare action``, the same first action of any kind (``analysis.words.actions_named``:
kick, punch, climb, sit, ...). ``--deepmimic DIR`` adds the DeepMimic clips of the ``pybullet``
wheel (kicks, punch, crawl, get-ups, ...) and Bandai dataset 1's kick and punch takes;
``--rate HZ`` writes each copy resampled to HZ (iClone's copies of CMU are at 60 Hz).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

BANDAI_TAKES = ("walk_normal_005", "run_normal_005", "wave-both-hands_normal_005",
                "wave-left-hand_active_005", "raise-up-right-hand_normal_005",
                "walk_elderly_010", "run_youthful_010", "walk-turn-left_normal_005",
                "walk_exhausted_010", "run_feminine_010")


def _bandai_file(bandai: Path, take: str) -> Path | None:
    hits = sorted(bandai.glob(f"**/dataset-2_{take}.bvh"))
    return hits[0] if hits else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="m2l")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--cmudev", default="/tmp/cmudev")
    ap.add_argument("--bandai", default="/tmp/bandai", help="the extracted Bandai archives")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--every", type=int, default=1, help="every n-th source only")
    ap.add_argument("--compare", choices=("gait", "action"), default="gait")
    ap.add_argument("--deepmimic", default=None, help="pybullet_data/data/motions, extracted")
    ap.add_argument("--rate", type=float, default=None, help="write each copy at this rate")
    args = ap.parse_args()

    import csv

    import torch

    import motionlang as ml
    from motionlang.analysis.words import actions_named
    from motionlang.datasets.named import cmu35_walkjog, cmu_dev_folder
    from motionlang.models.seq2seq.decode.grounded import named_gait

    def named(text: str) -> str | None:
        if args.compare == "gait":
            return named_gait(text)
        found = actions_named(text)
        return found[0] if found else None
    torch.set_num_threads(1)
    data, cmudev = Path(args.data), Path(args.cmudev)
    dev = cmu_dev_folder(data, cmudev)
    sources: list[tuple[str, object]] = []
    with open(data / "cmu_dev" / "trials.tsv", newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            if row["primary"] == "1":
                sources.append((row["file"], dev / row["file"]))
    sources += [(f"cmu35/{t.trial}", t.motion) for t in cmu35_walkjog(data).trials]
    bandai_rig = None
    for take in BANDAI_TAKES:
        path = _bandai_file(Path(args.bandai), take)
        if path is not None:
            sources.append((f"bandai/{take}", path))
            bandai_rig = bandai_rig or path
    if args.deepmimic is not None:
        sources += [(f"deepmimic/{p.stem}", p) for p in sorted(Path(args.deepmimic).glob("humanoid3d_*.txt"))]
        sources += [(f"bandai/{p.stem}", p) for p in sorted(Path(args.bandai).glob(
            "**/dataset-1_*[kp]*_normal_00*.bvh")) if p.stem.split("_")[1] in ("kick", "punch")]
    sources = sources[::args.every]
    rigs = {"bandai": bandai_rig, "iclone": dev / "iclone" / "05_01.bvh",
            "secondlife": dev / "secondlife" / "05_01.bvh",
            "makehuman": dev / "makehuman" / "05_01.bvh"}
    rigs = {k: ml.load_rig(v) for k, v in rigs.items() if v is not None}
    model = ml.load_model(args.model)
    same: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    misses = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, src in sources:
            motion = ml.read_motion(src) if isinstance(src, Path) else src
            motion = motion.between(0.0, min(args.seconds, motion.duration))
            first = named(ml.describe(motion, model, 5)[0][0])
            for rig_name, rig in rigs.items():
                copy = ml.retarget(motion, rig)
                if args.rate is not None:
                    copy = copy.resample(args.rate)
                out = ml.write_motion(copy, Path(tmp) / f"{rig_name}.bvh")
                text = ml.describe(ml.read_motion(out), model, 5)[0][0]
                ok = named(text) == first
                same[rig_name][0] += ok
                same[rig_name][1] += 1
                if not ok:
                    misses.append(f"{name} on {rig_name}: {first} -> {named(text)} "
                                  f"({text!r})")
            print(f"{name}: {first}", flush=True)
    print(f"\n{args.model}: the same first {args.compare} as the original ({len(sources)} "
          f"sources, first {args.seconds:g} s each"
          + (f", copies at {args.rate:g} Hz" if args.rate else "") + ")")
    total = [0, 0]
    for rig_name, (k, n) in same.items():
        total[0] += k
        total[1] += n
        print(f"  {rig_name:11s} {k:3d}/{n:3d} = {100 * k / n:5.1f} %")
    print(f"  {'all':11s} {total[0]:3d}/{total[1]:3d} = {100 * total[0] / total[1]:5.1f} %")
    for m in misses:
        print("  differs:", m)


if __name__ == "__main__":
    main()

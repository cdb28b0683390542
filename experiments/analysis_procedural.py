"""Each detector of ``motionlang.analysis`` against the procedural corpus' exact ground truth:
precision and recall per action, and how often sides and counts come out right.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/analysis_procedural.py [--n 300] [--seed 11]

A ground-truth primitive is found when a finding of its labels overlaps its frames; a finding
is right when it overlaps a primitive it stands for. Walk and run are scored on body
primitives of at least 1 s (the analysis needs a second of travel). ``stomp`` and ``wipe``
have no detector; findings during them count against precision of what they are taken for.
"""
from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

#: synthetic action -> the analysis labels that name it
LABELS = {"walk": ("walk",), "run": ("run",), "turn": ("turn", "spin"), "wave": ("wave",),
          "kick": ("kick",), "squat": ("squat", "crouch"), "jump": ("jump", "hop"),
          "raise_arms": ("raise",), "bow": ("bow", "bend"), "punch": ("punch",),
          "stand": ("stand",)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=300)
    ap.add_argument("--seed", type=int, default=11)
    args = ap.parse_args()
    from motionlang.analysis import analyse
    from motionlang.datasets.synth import generate_sample
    found = defaultdict(lambda: [0, 0])        # action -> [found, total]
    right = defaultdict(lambda: [0, 0])        # action -> [right, findings]
    side = defaultdict(lambda: [0, 0])
    count = defaultdict(lambda: [0, 0])
    for i in range(args.n):
        s = generate_sample(args.seed, i)
        fps = s.motion.fps
        a = analyse(s.motion)
        prims = [(p, p.start / fps, p.end / fps) for p in s.primitives]
        for p, t0, t1 in prims:
            if p.action not in LABELS or (p.action in ("walk", "run") and t1 - t0 < 1.0):
                continue
            hits = [f for f in a.findings if f.label in LABELS[p.action]
                    and min(t1, f.end) - max(t0, f.start) > 0]
            found[p.action][1] += 1
            found[p.action][0] += bool(hits)
            if hits and p.side in ("left", "right", "both") and p.action not in ("turn",):
                side[p.action][1] += 1
                side[p.action][0] += any(f.side == p.side for f in hits)
            if hits and p.count and p.action in ("wave", "kick", "squat", "jump", "punch", "bow"):
                count[p.action][1] += 1
                count[p.action][0] += any(f.count == p.count for f in hits)
        for f in a.findings:
            for act, labs in LABELS.items():
                if f.label in labs:
                    right[act][1] += 1
                    right[act][0] += any(p.action == act and min(t1, f.end) -
                                         max(t0, f.start) > 0 for p, t0, t1 in prims)
        if (i + 1) % 50 == 0:
            print(f"... {i + 1}/{args.n}", flush=True)
    print(f"\n{args.n} procedural samples (seed {args.seed})\n")
    print("| action | recall | precision | side right | count right |")
    print("|---|---|---|---|---|")

    def pct(x):
        return f"{100 * x[0] / x[1]:.0f} % ({x[0]}/{x[1]})" if x[1] else "-"
    for act in LABELS:
        print(f"| {act} | {pct(found[act])} | {pct(right[act])} | {pct(side[act])} | "
              f"{pct(count[act])} |")


if __name__ == "__main__":
    main()

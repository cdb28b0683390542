"""``describe --segments`` against a known timeline: long takes made by joining real Bandai
Namco test takes of different actions end to end (dataset 2: walk, run, turns, waves, raised
hands; each take moved to start where the previous one stopped, its heading left as
recorded), described as a timeline by the packaged M2L through ``ml.timeline``.

For every joined take it prints the true spans and the segments, and scores the timeline
over the take's time: the share of it where the segment names the true action's verb, and
its verb with the side (left, right, both), as ``library.timeline.action_of`` reads them
from the segment's sentence ("lift" counted as "raise", the label sentences' synonym).

With ``--cmu-dev DIR`` (``cmu_dev`` extracted) the takes are CMU trials of other subjects
instead, joined within one rig (Second Life: walks and jumps; iClone: forward, backward and
sideways dribbling walks), each labelled by CMU's description. Each joined take is also
scored by its boundaries: a true change of action counts as found when a segment boundary
lies within ``--tolerance`` seconds of it.

Run: .venv/bin/python benchmarks/describe_timeline.py [--takes 5] [--actions 4] [--seed 0]
     [--window 3] [--hop 1] [--bridge 1] [--merge action] [--cmu-dev DIR] [--tolerance 0.5]
"""
from __future__ import annotations

import argparse
import random
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import need_data  # noqa: E402

import motionlang as ml  # noqa: E402
from motionlang.datasets.bandai import load_bandai  # noqa: E402
from motionlang.kinematics.motion import concatenate  # noqa: E402
from motionlang.library.timeline import action_of  # noqa: E402

#: each content label of Bandai dataset 2 as ``action_of`` reads its sentences
TRUTH = {"walk": "walk", "walk-turn-left": "walk left", "walk-turn-right": "walk right",
         "run": "run", **{f"{verb}-{side}-{part}": f"{key} {side}"
                          for verb, key, part in (("wave", "wave", "hand"),
                                                  ("raise-up", "raise", "hand"))
                          for side in ("left", "right")},
         "wave-both-hands": "wave both", "raise-up-both-hands": "raise both"}
SYNONYMS = {"lift": "raise", "jog": "run", "sprint": "run", "hop": "jump", "leap": "jump",
            "step": "walk"}
#: cmu_dev files by rig, each with the verb (and side) its CMU description names
CMU_DEV = {
    "secondlife": {**{f"08_{i:02d}": "walk" for i in range(1, 12)},
                   **{f"12_{i:02d}": "walk" for i in range(1, 4)},
                   **{t: "jump" for t in ("13_11", "13_13", "13_32", "13_39", "13_40", "13_41",
                                          "13_42")}},
    "iclone": {"05_01": "walk", "06_01": "walk", "06_02": "walk", "06_03": "walk",
               "06_04": "walk", "06_05": "walk", "06_06": "walk back", "06_07": "walk back",
               "06_08": "walk", "06_09": "walk"},
}


def key_of(text: str, verb_only: bool) -> str:
    words = action_of(text).split()
    words[0] = SYNONYMS.get(words[0], words[0])
    return words[0] if verb_only else " ".join(words)


def join(motions: list) -> object:
    """The takes end to end, each moved on the floor to start where the last one ended."""
    moved, at = [], None
    for m in motions:
        root = m.root_translation.copy()
        if at is not None:
            root[:, [0, 2]] += at - root[0, [0, 2]]
        at = root[-1, [0, 2]]
        moved.append(m.replace(root_translation=root))
    return concatenate(moved, name="joined")


def agreement(truth: list[tuple[float, float, str]], segments: list, duration: float,
              verb_only: bool) -> float:
    """Share of ``duration`` (sampled every 0.1 s) where the segment's action is the
    truth's (``truth``: spans of :data:`TRUTH` keys)."""
    hits = []
    for t in np.arange(0.05, duration, 0.1):
        want = next(k for a, b, k in truth if a <= t < b or b >= duration)
        seg = next((s for s in segments if s.start <= t < s.end), segments[-1])
        hits.append(key_of(seg.text, verb_only) == (want.split()[0] if verb_only else want))
    return float(np.mean(hits))


def boundaries_found(truth: list[tuple[float, float, str]], segments: list,
                     tolerance: float) -> tuple[int, int]:
    """(true changes of action with a segment boundary within ``tolerance`` s, changes)."""
    changes = [b for (a, b, k), (_, _, k2) in zip(truth, truth[1:]) if k.split()[0] !=
               k2.split()[0]]
    cuts = [s.start for s in segments[1:]]
    return sum(any(abs(c - t) <= tolerance for c in cuts) for t in changes), len(changes)


def cmu_dev_takes(folder: Path, rng: random.Random, n_actions: int):
    """A list of (Motion, verb) from one rig of ``cmu_dev``, alternating between verbs."""
    rig = rng.choice(sorted(CMU_DEV))
    by_verb: dict[str, list[str]] = {}
    for trial, verb in CMU_DEV[rig].items():
        by_verb.setdefault(verb.split()[0], []).append(trial)
    verbs = sorted(by_verb)
    picked = []
    for i in range(n_actions):
        verb = verbs[i % len(verbs)] if len(verbs) > 1 else verbs[0]
        trial = rng.choice(by_verb[verb])
        picked.append((ml.read_motion(folder / rig / f"{trial}.bvh"), CMU_DEV[rig][trial],
                       f"{rig}/{trial}"))
    return picked


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--takes", type=int, default=5, help="joined takes (default 5)")
    ap.add_argument("--actions", type=int, default=4, help="actions a take (default 4)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--window", type=float, default=3.0)
    ap.add_argument("--hop", type=float, default=1.0)
    ap.add_argument("--bridge", type=int, default=1)
    ap.add_argument("--merge", choices=("action", "sentence"), default="action")
    ap.add_argument("--cmu-dev", type=Path, default=None, metavar="DIR",
                    help="join cmu_dev trials (the extracted cmu-dev folder) instead")
    ap.add_argument("--tolerance", type=float, default=0.5,
                    help="seconds within which a boundary counts as found")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    if args.cmu_dev is None:
        test = [r for r in load_bandai(need_data("bandai"), "test") if r.dataset == 2]
        contents = sorted({r.content for r in test})
    m2l = ml.load_model("m2l")
    scores: dict[str, list[float]] = {"verb": [], "verb and side": []}
    counts = []
    found = [0, 0]
    for n in range(args.takes):
        if args.cmu_dev is not None:
            parts = cmu_dev_takes(args.cmu_dev, rng, args.actions)
            motions = [m for m, _, _ in parts]
            labels = [(name, verb) for _, verb, name in parts]
        else:
            picked = [rng.choice([r for r in test if r.content == c])
                      for c in rng.sample(contents, args.actions)]
            motions = [ml.read_motion(r.path) for r in picked]
            labels = [(r.id, TRUTH[r.content]) for r in picked]
        take = join(motions)
        truth, t0 = [], 0.0
        for (_, verb), m in zip(labels, motions):
            truth.append((t0, t0 + m.n_frames / m.fps, verb))
            t0 += m.n_frames / m.fps
        started = time.perf_counter()
        segments = ml.timeline(take, m2l, window=args.window, hop=args.hop,
                               bridge=args.bridge, merge=args.merge)
        took = time.perf_counter() - started
        duration = take.n_frames / take.fps
        print(f"\ntake {n + 1}: {duration:.1f} s, {len(segments)} segments in {took:.1f} s")
        for (a, b, s), (name, _) in zip(truth, labels):
            print(f"  truth {a:5.1f}-{b:5.1f} s  {name}  ({s})")
        for s in segments:
            print(f"        {s.line()}")
        for name in scores:
            scores[name].append(agreement(truth, segments, duration, name == "verb"))
        counts.append(len(segments) / args.actions)
        hit, of = boundaries_found(truth, segments, args.tolerance)
        found[0] += hit
        found[1] += of
        print("  agreement: " + ", ".join(f"{k} {v[-1]:.0%}" for k, v in scores.items()) +
              f"; boundaries found {hit} of {of}")
    print(f"\n{args.takes} takes of {args.actions} actions (seed {args.seed}; window "
          f"{args.window:g} s, hop {args.hop:g} s, bridge {args.bridge}, merge "
          f"{args.merge}): " +
          ", ".join(f"{k} agreement mean {statistics.mean(v):.0%}" for k, v in scores.items())
          + f"; {statistics.mean(counts):.1f} segments per true action; changes of action "
          f"with a boundary within {args.tolerance:g} s: {found[0]} of {found[1]}")


if __name__ == "__main__":
    main()

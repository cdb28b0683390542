"""``generate --library`` on ten two-action sentences: is each action there (the open-world
check), do the joins slide or jump, and how do the packaged generators do on the same
sentences.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/compose_library.py /tmp/lib.idx \\
        [--render /tmp/compose] [--models l2m twostream masked]

For each sentence: the composed motion's check (each action the sentence names, shown or
not, by ``motionlang.analysis``); the foot skating (m/s, ``metrics.physics.foot_skating``)
inside each join (the overlap and 0.25 s either side) against the skating of the clips'
own frames, as a ratio; the largest root step (m a frame) and facing change (degrees a
frame) inside the joins against the largest the clips make themselves (each whole clip on
the composed body). ``--render``: a PNG strip of
each composed motion there, to look at. ``--models``: the same check on what each packaged
generator makes of the sentence.
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import motionlang as ml
from motionlang.analysis import check
from motionlang.evaluation.metrics.physics import foot_skating
from motionlang.features.body21 import stature21
from motionlang.features.positions import facing_yaw
from motionlang.library.compose import FPS, JOIN, _clip_positions, compose
from motionlang.library.search import Library
from motionlang.rendering.output import body_motion

SENTENCES = [
    "a person walks forward, then kicks",
    "a person walks forward, then punches",
    "a person runs, then jumps",
    "a person walks, then balances on one leg",
    "a person walks forward, then waves",
    "a person walks, then bows",
    "a person runs, then walks",
    "a person jumps, then runs",
    "a person walks forward, then raises both hands",
    "a person kicks, then walks away",
]
MARGIN = 0.25


def steps(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T-1,) root step lengths (m) and facing changes (degrees) frame to frame."""
    root = np.linalg.norm(np.diff(p[:, 0, [0, 2]], axis=0), axis=1)
    turn = np.degrees(np.abs(np.diff(np.unwrap(facing_yaw(p)))))
    return root, turn


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("index")
    ap.add_argument("--render", help="a folder for a PNG strip of each composed motion")
    ap.add_argument("--models", nargs="*", default=[], help="packaged generators to compare")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    lib = Library.open(args.index)
    shown = {"library": 0, **{m: 0 for m in args.models}}
    ratios, jumps = [], []
    for n, text in enumerate(SENTENCES, 1):
        made = compose(text, lib)
        p = made.positions
        motion = body_motion(p, made.fps)[0]
        got = check(text, motion)
        ok = all(c.shown for c in got)
        shown["library"] += ok
        overlap = int(round(JOIN * FPS))
        inside = np.zeros(len(p) - 1, dtype=bool)
        skate = []
        for s in made.joins:
            a, b = max(0, s - int(MARGIN * FPS)), min(len(p), s + overlap + int(MARGIN * FPS))
            inside[a:b - 1] = True
            skate.append(foot_skating(p[a:b], FPS))
        own = [foot_skating(_clip_positions(lib, c, None), FPS) for c in made.clips]
        ratio = float(np.nanmean(skate) / np.nanmean(own))
        ratios.append(ratio)
        root, turn = steps(p)
        # against the largest the clips make themselves (the whole clip, on the composed
        # body): a clip that ends in a spin turns as fast inside its join as before it
        own_steps = [steps(_clip_positions(lib, c, stature21(p))) for c in made.clips]
        jump = (root[inside].max() / max(max(r.max() for r, _ in own_steps), 1e-6),
                turn[inside].max() / max(max(t.max() for _, t in own_steps), 1e-6))
        jumps.append(jump)
        print(f"{n:2d}. {text}\n    clips: " + "; ".join(
            f"{c.file} {c.start:.1f}-{c.end:.1f} s ({c.why or 'learned'})" for c in made.clips))
        print("    check: " + ", ".join(c.line() for c in got))
        print(f"    joins: skating {np.nanmean(skate):.3f} m/s against the clips' "
              f"{np.nanmean(own):.3f} (x{ratio:.2f}); largest root step x{jump[0]:.2f}, "
              f"facing change x{jump[1]:.2f} of the clips' own largest")
        if args.render:
            out = Path(args.render)
            out.mkdir(parents=True, exist_ok=True)
            ml.write_motion(motion, out / f"{n:02d}.bvh")
            from motionlang.rendering.output import write_result
            write_result(p, out / f"{n:02d}.png", fps=made.fps, title=text)
        for m in args.models:
            gen = ml.generate(text, m)
            shown[m] += all(c.shown for c in check(text, gen))
    print("\nevery action shown: " + ", ".join(f"{k} {v} of {len(SENTENCES)}"
                                                for k, v in shown.items()))
    print(f"join skating / clips' own: median x{np.median(ratios):.2f}, worst "
          f"x{max(ratios):.2f}; root step at joins / clips' largest: worst "
          f"x{max(j[0] for j in jumps):.2f}; facing change: worst x{max(j[1] for j in jumps):.2f}")


if __name__ == "__main__":
    main()

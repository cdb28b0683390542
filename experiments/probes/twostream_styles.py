"""Which styles does each model's motion carry, by the judge and by plain measures? For each
Bandai validation take, each model makes the motion of the take's sentence (as long as the
take, feet locked as ``evaluate-judge`` does), and per asked style this prints the judge's
recognition rate and three measures taken on the motion itself beside the real takes' own:
the root's mean speed over the ground (m/s), the hands' mean height over the root (m), the
joints' mean speed relative to the root (m/s) and the ankles' mean distance apart along the
hips' axis (m), each less its mean over the motions of the
same asked content (the style's share, not the action's). Where the judge and the plain measures
disagree about a model, the measures say whether its motions differ by style at all: the
correlation, over the styles, of a model's per-style means with the real takes', and how
widely its per-style means spread against theirs.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_styles.py \\
        --model packaged=twostream --model src=runs/ts_bs_e2_sources.pt [--limit 0]
"""
from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MEASURES = ("root speed", "hands over root", "joint speed", "step width")


def measures(p, fps: float):
    """(T, 21, 3) metres, Y up -> the :data:`MEASURES`."""
    import numpy as np

    from motionlang.features.joint_map import KIT21_NAMES
    hands = [KIT21_NAMES.index(n) for n in ("LW", "RW")]
    root = p[:, 0]
    ground = np.linalg.norm(np.diff(root[:, [0, 2]], axis=0), axis=-1).mean() * fps
    over = (p[:, hands, 1] - root[:, None, 1]).mean()
    local = p - root[:, None]
    speed = np.linalg.norm(np.diff(local, axis=0), axis=-1).mean() * fps
    # the ankles' distance apart along the hips' horizontal axis
    lh, rh, la, ra = (KIT21_NAMES.index(n) for n in ("LH", "RH", "LA", "RA"))
    axis = (p[:, rh] - p[:, lh])[:, [0, 2]]
    axis /= np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-9)
    width = np.abs(((p[:, ra] - p[:, la])[:, [0, 2]] * axis).sum(-1)).mean()
    return float(ground), float(over), float(speed), float(width)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", action="append", required=True, help="NAME=MODEL")
    ap.add_argument("--judge", default="judge")
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--split", default="val")
    ap.add_argument("--limit", type=int, default=0, help="at most this many takes (0: all)")
    a = ap.parse_args(argv)
    import numpy as np
    import torch

    import motionlang as ml
    from motionlang.evaluation.sampling import stratified_sample
    from motionlang.features.foot_lock import lock_feet
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.registry import load_model
    from motionlang.models.t2m import FPS
    torch.set_num_threads(1)
    judge = load_model(a.judge, kind="judge")
    real = bandai_items(a.bandai, a.split, fps=FPS)
    sentences = bandai_sentences(a.bandai, a.split)
    keep = stratified_sample(len(real), a.limit, [s.content for s in sentences], seed=0)
    real, sentences = [real[i] for i in keep], [sentences[i] for i in keep]
    asked = [s.style if s.states_style else None for s in sentences]
    contents = [s.content for s in sentences]
    styles = sorted({s for s in asked if s})
    motions = {"real": [it.positions for it in real]}
    for spec in a.model:
        name, _, path = spec.partition("=")
        t2m = ml.text_to_motion(path)
        motions[name] = [lock_feet(t2m.positions21(s.text, max(2, len(it.positions))), FPS)
                         for s, it in zip(sentences, real)]
        print(f"{name}: {len(motions[name])} motions", file=sys.stderr, flush=True)
    table, answers = {}, {}
    for name, ps in motions.items():
        got = judge.judge(ps, FPS)["style"]
        said = [judge.config.styles[int(np.argmax(g))] for g in got]
        right = [a == s for a, s in zip(said, asked)]
        answers[name] = {s: Counter(a for a, x in zip(said, asked) if x == s).most_common(2)
                         for s in styles}
        m = np.array([measures(p, FPS) for p in ps])
        # against the mean of the same content's motions: what the style adds to the action
        for c in set(contents):
            mine = np.array([x == c for x in contents])
            m[mine] -= m[mine].mean(0)
        table[name] = {s: (np.mean([r for r, x in zip(right, asked) if x == s]),
                           m[[x == s for x in asked]].mean(0)) for s in styles}
    names = list(motions)
    print(f"{len(real)} Bandai {a.split} takes; per asked style: judge's style recognition % "
          f"(real: the judge's own accuracy), then {', '.join(MEASURES)}, each less "
          "its content's mean\n")
    print("| style | n | " + " | ".join(f"{n} judge %" for n in names) + " | "
          + " | ".join(f"{n} {m}" for m in MEASURES for n in names) + " |")
    print("|---" * (2 + len(names) * (1 + len(MEASURES))) + "|")
    for s in styles:
        n = sum(x == s for x in asked)
        cells = [f"{100 * table[k][s][0]:.0f}" for k in names]
        cells += [f"{table[k][s][1][j]:.3f}" for j in range(len(MEASURES)) for k in names]
        print(f"| {s} | {n} | " + " | ".join(cells) + " |")
    print("\nthe judge's two most frequent answers per asked style:")
    for k in names[1:]:
        print(f"  {k}: " + "; ".join(f"{s} -> " + ", ".join(f"{a} {n}" for a, n in answers[k][s])
                                     for s in styles))
    print("\nover the styles, each model's per-style means against the real takes': their "
          "correlation r and their spread (std) as a multiple of the real takes'")
    for k in names[1:]:
        cells = []
        for j, m in enumerate(MEASURES):
            ref = np.array([table["real"][s][1][j] for s in styles])
            mine = np.array([table[k][s][1][j] for s in styles])
            cells.append(f"{m} r {np.corrcoef(ref, mine)[0, 1]:.2f}, "
                         f"spread x{mine.std() / ref.std():.2f}")
        print(f"  {k}: " + "; ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Which asked actions does a text-to-motion model's motion miss, by the judge, and how do its
turns compare with the real takes'? For each Bandai validation take the model makes the motion
of the take's sentence (as long as the take, feet locked as ``evaluate-judge`` does); per asked
content this prints the judge's recognition and its most frequent answers, then for the
turning contents the heading change over the motion (degrees: the hips' axis, last 5 frames
against the first 5) and the peak turning rate (degrees a second, the heading smoothed over
5 frames), real against generated (medians over the takes).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_actions.py --model twostream
"""
from __future__ import annotations

import argparse
import sys
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def turn(p, fps: float) -> tuple[float, float]:
    """(T, 21, 3) metres, Y up -> (heading change in degrees, peak turning rate in deg/s)."""
    import numpy as np

    from motionlang.features.joint_map import KIT21_NAMES
    axis = p[:, KIT21_NAMES.index("RH")] - p[:, KIT21_NAMES.index("LH")]
    heading = np.degrees(np.unwrap(np.arctan2(axis[:, 2], axis[:, 0])))
    smooth = np.convolve(heading, np.ones(5) / 5, mode="valid")
    rate = np.abs(np.diff(smooth)).max() * fps if len(smooth) > 1 else 0.0
    return float(heading[-5:].mean() - heading[:5].mean()), float(rate)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--judge", default="judge")
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--split", default="val")
    a = ap.parse_args(argv)
    import numpy as np
    import torch

    import motionlang as ml
    from motionlang.features.foot_lock import lock_feet
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.registry import load_model
    from motionlang.models.t2m import FPS
    torch.set_num_threads(1)
    judge = load_model(a.judge, kind="judge")
    real = bandai_items(a.bandai, a.split, fps=FPS)
    sentences = bandai_sentences(a.bandai, a.split)
    t2m = ml.text_to_motion(a.model)
    made = [lock_feet(t2m.positions21(s.text, max(2, len(it.positions))), FPS)
            for s, it in zip(sentences, real)]
    got = judge.judge(made, FPS)["content"]
    said = [judge.config.contents[int(np.argmax(g))] for g in got]
    answers = defaultdict(list)
    for s, x in zip(sentences, said):
        answers[s.content].append(x)
    print(f"{len(real)} Bandai {a.split} takes, {a.model}: the asked action recognised in "
          f"{100 * np.mean([x == s.content for x, s in zip(said, sentences)]):.1f} %\n")
    print("| asked action | takes | recognised | the judge's answers |\n|---|---|---|---|")
    for c, xs in sorted(answers.items(), key=lambda kv: np.mean([x == kv[0] for x in kv[1]])):
        print(f"| {c} | {len(xs)} | {100 * np.mean([x == c for x in xs]):.0f} % | "
              + ", ".join(f"{x} {n}" for x, n in Counter(xs).most_common(3)) + " |")
    print("\n| asked action | heading change real / generated (deg) | peak turning rate real / "
          "generated (deg/s) |\n|---|---|---|")
    for c in sorted(answers):
        if "turn" not in c:
            continue
        idx = [i for i, s in enumerate(sentences) if s.content == c]
        r = np.array([turn(real[i].positions, FPS) for i in idx])
        g = np.array([turn(made[i], FPS) for i in idx])
        print(f"| {c} | {np.median(r[:, 0]):.0f} / {np.median(g[:, 0]):.0f} | "
              f"{np.median(r[:, 1]):.0f} / {np.median(g[:, 1]):.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

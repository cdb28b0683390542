"""How much of a style is in the first pose? A two-stream model's motions for the Bandai
validation takes asked in some styles, started from four first poses, and how often the judge
recognises the asked style and action in each:

- ``rest``: the model's one rest pose (the mean first frame of its training motions);
- ``bandai``: the mean first frame of the Bandai training takes;
- ``real``: the take's own first frame (the take's: not a fair test, an upper mark);
- ``sentence``: the pose read from the sentence (``models.twostream.start``, fitted here as
  the recipe fits it, or the model's own where it has one).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_first_pose.py \\
        runs/ts_bs_e5_sources.pt --corpus runs/twostream_parts/corpus [--styles feminine,active]
"""
from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model")
    ap.add_argument("--corpus", required=True, help="the run's procedural corpus")
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--styles", default="feminine,active", help="asked styles (comma-separated)")
    a = ap.parse_args(argv)
    import numpy as np
    import torch

    import motionlang as ml
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.features.foot_lock import lock_feet
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.registry import load_model
    from motionlang.models.t2m import FPS
    from motionlang.models.twostream.start import fit_start_pose
    torch.set_num_threads(1)
    model = ml.load_model(a.model).eval()
    data = build_twostream_data([a.corpus, f"bandai:{a.bandai}"], seed=0, max_seconds=30.0,
                                by_source=-1 if model.sources is not None else None)
    own = [it for it in data.items["train"] if not it.get("mirrored")]
    fitted = model.start_pose or fit_start_pose(model, [it["sentence"] for it in own],
                                                np.stack([it["motion"][0] for it in own]))
    bandai_first = np.stack([data.sequences[i][0] for i in data.splits["train"]
                             if data.sources.get(i) == 1]).mean(0)
    judge = load_model("judge", kind="judge")
    real = bandai_items(a.bandai, "val", fps=FPS)
    sentences = bandai_sentences(a.bandai, "val")
    want = a.styles.split(",")
    idx = [i for i, s in enumerate(sentences) if s.states_style and s.style in want]
    for mode in ("rest", "bandai", "real", "sentence"):
        model.start_pose = fitted if mode == "sentence" else None
        motions = []
        for i in idx:
            n, start = max(2, len(real[i].positions)), None
            if mode == "real":
                start = torch.as_tensor(model.features_from_positions(real[i].positions[:2])[0])
            elif mode == "bandai":   # Bandai's statistics: the model's one output space
                start = torch.as_tensor(bandai_first, dtype=torch.float32)
            motions.append(lock_feet(model.positions(model.generate(sentences[i].text, n,
                                                                    start=start)), FPS))
        got = judge.judge(motions, FPS)
        style = [judge.config.styles[int(np.argmax(g))] for g in got["style"]]
        content = [judge.config.contents[int(np.argmax(g))] for g in got["content"]]
        print(f"{mode}: {len(idx)} takes, style recognised "
              f"{100 * np.mean([s == sentences[i].style for s, i in zip(style, idx)]):.1f} %, "
              f"action {100 * np.mean([c == sentences[i].content for c, i in zip(content, idx)]):.1f}"
              f" %; the judge's answers {Counter(style).most_common(3)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

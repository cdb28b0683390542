"""Give a trained two-stream model what the recipe now fits at the end of every run: the first
pose from the sentence (``models.twostream.start``), and for a model trained with
``--normalise by-source`` each source's normaliser and the regression from the sentence
embedding to the source (``models.twostream.sources``), so each sentence's motion starts in a
posture of its kind and comes out in the statistics of the source it reads like. For models
trained before (``runs/ts_by_source``, the package). Prints how often the regression names
the right source of the validation and test sentences.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_fit_heads.py \\
        MODEL OUT --corpus runs/twostream_parts/corpus [--no-start-pose] [--no-sources]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--corpus", required=True, help="the run's procedural corpus")
    ap.add_argument("--bandai", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--no-start-pose", action="store_true", help="no first pose from the "
                    "sentence (the rest pose, as before)")
    ap.add_argument("--ridge", type=float, default=1.0, help="the first pose's penalty")
    ap.add_argument("--no-sources", action="store_true", help="a by-source model: all its "
                    "motions in its features' source's statistics, as before")
    a = ap.parse_args(argv)
    import numpy as np
    import torch

    import motionlang as ml
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.models.twostream.sources import embed, fit_source_output
    from motionlang.models.twostream.start import fit_start_pose
    torch.set_num_threads(1)
    model = ml.load_model(a.model)
    data = build_twostream_data([a.corpus, f"bandai:{a.bandai}"], seed=0, max_seconds=30.0)
    if not np.allclose(model.normalizer.mean, data.features.normalizer.mean, atol=1e-6):
        data = build_twostream_data([a.corpus, f"bandai:{a.bandai}"], seed=0,
                                    max_seconds=30.0, by_source=-1)
        if not np.allclose(model.normalizer.mean, data.features.normalizer.mean, atol=1e-6):
            print(f"{a.model}: not a model of this mix (its normaliser is neither the mix's "
                  "nor the Bandai takes' own)", file=sys.stderr)
            return 2
    own = [it for it in data.items["train"] if not it.get("mirrored")]
    sentences = [it["sentence"] for it in own]
    model.start_pose = None if a.no_start_pose else fit_start_pose(
        model, sentences, np.stack([it["motion"][0] for it in own]), ridge=a.ridge)
    if data.normalizers and not a.no_sources:
        model.sources = fit_source_output(model, sentences, [data.sources[it["id"]] for it in own],
                                          data.normalizers)
        for split in ("val", "test"):
            items = data.items[split]
            p = model.sources.probabilities(torch.as_tensor(
                embed(model, [it["sentence"] for it in items])))
            truth = np.array([data.sources[it["id"]] for it in items])
            for s, name in enumerate(("procedural", "Bandai")):
                mine = truth == s
                print(f"{split} {name}: {mine.sum()} sentences, source named right "
                      f"{100 * (p.argmax(-1).numpy()[mine] == s).mean():.1f} %, mean "
                      f"probability {float(p[torch.as_tensor(mine), s].mean()):.3f}")
    model.save(a.out)
    print(f"saved {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

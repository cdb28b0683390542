"""Give a two-stream model trained with ``--normalise by-source`` before the recipe kept every
source's normaliser (``runs/ts_by_source``) what the recipe now fits at the end of such a run:
each source's normaliser and the regression from the sentence embedding to the source
(``models.twostream.sources``), so each sentence's motion comes out in the statistics of the
source it reads like. Prints how often the regression names the right source of the
validation and test sentences.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_source_output.py \\
        runs/ts_bs_e2/model.pt runs/ts_bs_e2_sources.pt --corpus runs/twostream_parts/corpus
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
    a = ap.parse_args(argv)
    import numpy as np
    import torch

    import motionlang as ml
    from motionlang.datasets.twostream_items import build_twostream_data
    from motionlang.models.twostream.sources import fit_source_output
    torch.set_num_threads(1)
    data = build_twostream_data([a.corpus, f"bandai:{a.bandai}"], seed=0, max_seconds=30.0,
                                by_source=-1)
    model = ml.load_model(a.model)
    if not np.allclose(model.normalizer.mean, data.features.normalizer.mean, atol=1e-6):
        print(f"{a.model}: its normaliser is not the Bandai takes' own: not a by-source run",
              file=sys.stderr)
        return 2
    train = data.items["train"]
    model.sources = fit_source_output(model, [it["sentence"] for it in train],
                                      [data.sources[it["id"]] for it in train],
                                      data.normalizers)
    for split in ("val", "test"):
        items = data.items[split]
        with torch.no_grad():
            p = torch.cat([model.sources.probabilities(model.joint(model.encode_text(
                [it["sentence"] for it in items[i:i + 256]]))) for i in range(0, len(items), 256)])
        truth = np.array([data.sources[it["id"]] for it in items])
        for s, name in enumerate(("procedural", "Bandai")):
            mine = truth == s
            print(f"{split} {name}: {mine.sum()} sentences, source named right "
                  f"{100 * (p.argmax(-1).numpy()[mine] == s).mean():.1f} %, mean probability "
                  f"{float(p[torch.as_tensor(mine), s].mean()):.3f}")
    model.save(a.out)
    print(f"saved {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

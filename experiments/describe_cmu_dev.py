"""``describe`` on every file of ``cmu_dev`` (real CMU trials of other subjects in three
rigs): the model's own first sentence, the checked one, and how many first sentences name a
style or mood, repeat themselves or have no verb (issue 57's counts).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/describe_cmu_dev.py /tmp/cmu_dev/cmu-dev
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="the extracted cmu-dev folder (trials.tsv)")
    ap.add_argument("--model", default="m2l")
    args = ap.parse_args()
    import torch

    import motionlang as ml
    from motionlang.analysis import repeats
    from motionlang.datasets.bandai_text import styles_named
    from motionlang.models.seq2seq.decode.grounded import GENDERED, has_verb
    torch.set_num_threads(1)
    model = ml.load_model(args.model)
    rows = [line.split("\t") for line in
            (args.folder / "trials.tsv").read_text().splitlines()[1:]]
    n = style = rep = verbless = gendered = 0
    for r in rows:
        motion = ml.read_motion(args.folder / r[1])
        raw = ml.describe(motion, model, 5, raw=True)[0][0]
        first = ml.describe(motion, model, 5)[0][0]
        n += 1
        style += bool(styles_named(first))
        rep += repeats(first)
        verbless += not has_verb(first)
        gendered += any(w in GENDERED for w in first.lower().split())
        print(f"{r[1]}\t{r[5]}\t{raw}\t{first}", flush=True)
    print(f"files {n}; first sentences with a style word {style}; repeated {rep}; "
          f"without a verb {verbless}; naming a gender {gendered}")


if __name__ == "__main__":
    main()

"""``describe`` on every file of ``cmu_dev`` (real CMU trials of other subjects in three
rigs): the model's own first sentence, the checked one, and how many first sentences name a
style or mood, repeat themselves or have no verb (issue 57's counts), and how many of all the
sentences ``describe`` lists are broken English (``analysis.garbled``). Each file is read
from its path, at the rate its body or its export says, as ``describe FILE`` reads it.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/describe_cmu_dev.py /tmp/cmu_dev/cmu-dev

``--count captions.jsonl`` counts instead the broken and gendered sentences of what
``describe DIR -o captions.jsonl`` wrote (of any version of motionlang).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, nargs="?",
                    help="the extracted cmu-dev folder (trials.tsv)")
    ap.add_argument("--model", default="m2l")
    ap.add_argument("--count", type=Path, metavar="JSONL")
    args = ap.parse_args()
    if args.count:
        count(args.count)
        return
    import torch

    import motionlang as ml
    from motionlang.analysis import garbled, repeats
    from motionlang.datasets.bandai_text import styles_named
    from motionlang.models.seq2seq.decode.grounded import GENDERED, has_verb
    torch.set_num_threads(1)
    model = ml.load_model(args.model)
    rows = [line.split("\t") for line in
            (args.folder / "trials.tsv").read_text().splitlines()[1:]]
    n = style = rep = verbless = gendered = broken = listed = 0
    for r in rows:
        path = args.folder / r[1]
        raw = ml.describe(path, model, 5, raw=True)[0][0]
        said = [t for t, _ in ml.describe(path, model, 5)]
        first = said[0]
        listed += len(said)
        broken += sum(garbled(t) for t in said)
        n += 1
        style += bool(styles_named(first))
        rep += repeats(first)
        verbless += not has_verb(first)
        gendered += any(w in GENDERED for w in first.lower().split())
        print(f"{r[1]}\t{r[5]}\t{raw}\t{first}", flush=True)
    print(f"files {n}; first sentences with a style word {style}; repeated {rep}; "
          f"without a verb {verbless}; naming a gender {gendered}; of all {listed} "
          f"sentences listed, broken English {broken}")


def count(path: Path) -> None:
    import json

    from motionlang.analysis import garbled
    from motionlang.models.seq2seq.decode.grounded import GENDERED
    records = [json.loads(line) for line in path.read_text().splitlines()]
    said = [s["text"] for r in records if "file" in r for s in r.get("sentences", [])]
    print(f"{sum('file' in r for r in records)} files, {len(said)} sentences; broken "
          f"English {sum(map(garbled, said))}; naming a gender "
          f"{sum(any(w in GENDERED for w in t.lower().split()) for t in said)}")


if __name__ == "__main__":
    main()

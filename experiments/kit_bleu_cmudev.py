"""BLEU of `describe` against KIT-ML's sentences for the `cmu_dev` trials that KIT-ML annotates
(issue 41: "BLEU-4 against the trials' KIT-ML sentences is 0.000, the constant 0.049").

    OMP_NUM_THREADS=1 .venv/bin/python experiments/kit_bleu_cmudev.py [--model m2l ...]
        [--data ../shared/data] [--cmudev /tmp/cmudev]

The trials of ``cmu_dev/trials.tsv`` with KIT-ML ids (16: four ballet takes, eleven walks of
subject 08, one jump-and-reach); references: every annotation of those ids in
``kitml/annotations_tmr.json``; hypotheses: the first sentence of ``describe`` (checked, and
``--raw``) and the constant "a person walks forward". Corpus BLEU-1 and BLEU-4 (NLTK, method-1
smoothing), lower case, words only.
"""
from __future__ import annotations

import argparse
import csv
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def words(text: str) -> list[str]:
    return re.findall(r"[a-z0-9]+", text.lower())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", action="append")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--cmudev", default="/tmp/cmudev")
    args = ap.parse_args()

    import torch
    from nltk.translate.bleu_score import SmoothingFunction, corpus_bleu

    import motionlang as ml
    from motionlang.datasets.named import cmu_dev_folder
    torch.set_num_threads(1)
    data, cmudev = Path(args.data), Path(args.cmudev)
    cmu_dev_folder(data, cmudev)
    kit = json.loads((data / "kitml" / "annotations_tmr.json").read_text())
    trials = []
    with open(data / "cmu_dev" / "trials.tsv", newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            refs = [words(a["text"]) for k in row["kit_ids"].split() if k in kit
                    for a in kit[k]["annotations"]]
            if refs:
                trials.append((row["trial"], cmudev / "cmu-dev" / row["file"], refs))
    smooth = SmoothingFunction().method1
    refs = [r for _, _, r in trials]

    def bleu(hyps):
        return (corpus_bleu(refs, hyps, weights=(1, 0, 0, 0), smoothing_function=smooth),
                corpus_bleu(refs, hyps, smoothing_function=smooth))

    b1, b4 = bleu([words("a person walks forward")] * len(trials))
    print(f"{len(trials)} trials, {sum(map(len, refs))} KIT-ML sentences")
    print(f"constant 'a person walks forward': BLEU-1 {b1:.3f}  BLEU-4 {b4:.3f}")
    for spec in args.model or ["m2l", "m2l-procedural"]:
        model = ml.load_model(spec)
        for raw in (True, False):
            texts = [ml.describe(p, model, 5, raw=raw)[0][0] for _, p, _ in trials]
            b1, b4 = bleu([words(t) for t in texts])
            print(f"{spec}{' --raw' if raw else ''}: BLEU-1 {b1:.3f}  BLEU-4 {b4:.3f}")
            for (trial, _, r), t in zip(trials, texts):
                print(f"   {trial}: {t}   | KIT: {' '.join(r[0])}")


if __name__ == "__main__":
    main()

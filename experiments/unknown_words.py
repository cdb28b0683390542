"""Real sentences in words the L2M's training captions never use (issue #41, item 5): how many
of their words the packaged L2Ms cannot read, before and after unknown words are read as the
nearest known word (``models.word_map``), and what each was read as.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/unknown_words.py \
        [--kit ../shared/data/kitml/annotations_tmr.json] [--n-kit 60] [--seed 41] \
        [--cmu ../shared/data/cmu_dev/trials.tsv] [--model l2m --model l2m-procedural] \
        [--vectors minilm --vectors glove]

The sentences: a seeded sample of KIT-ML annotations (another lab's annotators; the packaged
models learnt procedural and Bandai captions only) and every distinct CMU description of
``cmu_dev``. A word is counted once per occurrence (tokens after ``datasets.text.tokenize``,
spelling corrections included). Prints a Markdown table per vector source and the words
read as others with their similarity. The asked action on synonym-swapped Bandai sentences
with and without the mapping is ``experiments/paraphrase_judge.py``'s.
"""
from __future__ import annotations

import argparse
import csv
import json
import random
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"


def kit_sentences(path: Path, n: int, seed: int) -> list[str]:
    """``n`` annotations drawn with ``seed`` from KIT-ML's annotation file (sorted first, so
    the draw does not depend on the file's order)."""
    data = json.loads(path.read_text(encoding="utf-8"))
    texts = sorted({a["text"] for item in data.values() for a in item.get("annotations", [])})
    return random.Random(seed).sample(texts, n)


def cmu_sentences(path: Path) -> list[str]:
    """The distinct CMU descriptions of ``trials.tsv``, in file order."""
    with path.open(encoding="utf-8", newline="") as fh:
        rows = csv.DictReader(fh, delimiter="\t")
        return list(dict.fromkeys(r["cmu_description"].strip() for r in rows
                                  if r["cmu_description"].strip()))


def shares(mapper, vocab, sentences: list[str]) -> dict:
    """Word counts before and after mapping, and the mappings made."""
    from motionlang.datasets.text import tokenize
    from motionlang.models.word_map import FUNCTION_WORDS
    function = 0
    total = before = after = with_unknown_before = with_unknown_after = 0
    mapped: Counter = Counter()
    for s in sentences:
        tokens = tokenize(s)
        reading = mapper.read(tokens, s)
        kept = set(reading.unknown)
        n_before = sum(t not in vocab for t in tokens)
        n_after = sum(t in kept for t in tokens)
        function += sum(t in kept and t in FUNCTION_WORDS for t in tokens)
        total, before, after = total + len(tokens), before + n_before, after + n_after
        with_unknown_before += n_before > 0
        with_unknown_after += n_after > 0
        for w, k, sim in reading.mapped:
            mapped[(w, k, round(sim, 2))] += sum(t == w for t in tokens)
    return {"words": total, "before": before, "after": after, "mapped": mapped,
            "function": function,
            "sentences": len(sentences), "sent_before": with_unknown_before,
            "sent_after": with_unknown_after}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--kit", type=Path, default=DATA / "kitml" / "annotations_tmr.json")
    p.add_argument("--n-kit", type=int, default=60)
    p.add_argument("--seed", type=int, default=41)
    p.add_argument("--cmu", type=Path, default=DATA / "cmu_dev" / "trials.tsv")
    p.add_argument("--model", action="append", help="packaged L2M, file or run folder "
                   "(repeatable; default l2m and l2m-procedural)")
    p.add_argument("--vectors", action="append", help="word vectors (repeatable; default "
                   "minilm and glove)")
    args = p.parse_args()

    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.models.word_map import WordMapper

    sets = {"KIT-ML": kit_sentences(args.kit, args.n_kit, args.seed),
            "CMU": cmu_sentences(args.cmu)}
    sets["all"] = sets["KIT-ML"] + sets["CMU"]
    print(f"{len(sets['KIT-ML'])} KIT-ML annotations (seed {args.seed}), {len(sets['CMU'])} "
          f"CMU descriptions")
    for vectors in args.vectors or ["minilm", "glove"]:
        print(f"\n### vectors {vectors}\n")
        print("| model | sentences | words | unknown before | unknown after | sentences with "
              "an unknown word before / after | function words among those unknown after |")
        print("|---|---|---|---|---|---|---|")
        examples: dict[str, Counter] = {}
        for name in args.model or ["l2m", "l2m-procedural"]:
            model = ml.load_model(name, kind="l2m")
            mapper = WordMapper.of_vocabulary(model.vocab, vectors=vectors)
            for label, sentences in sets.items():
                r = shares(mapper, model.vocab, sentences)
                print(f"| {name} | {label} ({r['sentences']}) | {r['words']} | "
                      f"{r['before']} ({100 * r['before'] / r['words']:.1f} %) | "
                      f"{r['after']} ({100 * r['after'] / r['words']:.1f} %) | "
                      f"{r['sent_before']} / {r['sent_after']} | {r['function']} |")
                if label == "all":
                    examples[name] = r["mapped"]
        for name, mapped in examples.items():
            print(f"\n{name}, words read as others (occurrences): " + ", ".join(
                f"{w} -> {k} ({s:.2f}) x{n}" for (w, k, s), n in sorted(mapped.items())))


if __name__ == "__main__":
    main()

"""``motionlang search`` on the Bandai test takes with queries in other words: what a user
gets from an index of the 556 takes ``retrieval_bandai.py`` ranks whole (its windows,
merged spans and, with ``--grounded``, the analysis stored in the index), the query read as
the model reads it.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/search_bandai.py --work /tmp/btest \\
        [--data bandai:../shared/data/bandai] [--model retrieval] \\
        [--queries fixed experiments/queries/bandai_paraphrases_b.tsv ...]

``--work``: a folder for the takes (symlinks to the Bandai files) and their index, made on
the first run and brought up to date after. Each query's five best distinct takes are its
hits; a hit is right when the take's Bandai label (its file name) is the query's action.
``fixed`` (the default): the ten fixed queries of ``retrieval_bandai.py``. Each set is scored
both ways (the learned model alone, and with the analysis). Bandai data: CC BY-NC.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

import motionlang as ml
from motionlang.datasets.evaluator_items import build_evaluator_data
from motionlang.datasets.seq2seq_pairs import load_records
from motionlang.evaluation.t2m.yardstick import test_pairs

sys.path.insert(0, str(Path(__file__).resolve().parent))
from retrieval_bandai import read_queries  # noqa: E402


def test_takes(data: str) -> dict[Path, str]:
    """Path -> Bandai content label of each take the yardstick's test pairs hold."""
    tests = [r for r in load_records(data, 30.0) if r.split == "test"]
    built = build_evaluator_data(tests, "kit", seed=0, bones=None)
    records = [built.records[p["id"]] for p in test_pairs(built.items["test"], 0)]
    return {Path(r.path): r.labels["content"] for r in records}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", required=True, help="folder for the takes' links and index")
    ap.add_argument("--data", default="bandai:../shared/data/bandai", help="Bandai source")
    ap.add_argument("--model", default=None, help="the index's model (default: retrieval)")
    ap.add_argument("--queries", nargs="+", default=["fixed"],
                    help="files of action<TAB>query lines, or 'fixed': the ten fixed queries "
                         "(the default)")
    ap.add_argument("--k", type=int, default=5, help="hits scored per query")
    args = ap.parse_args(argv)

    labelled = test_takes(args.data)
    labels = {p.name: content for p, content in labelled.items()}
    work = Path(args.work)
    takes = work / "takes"
    takes.mkdir(parents=True, exist_ok=True)
    for p in labelled:
        if not (takes / p.name).exists():
            (takes / p.name).symlink_to(p.resolve())
    index = work / "takes.idx"
    print(ml.index(takes, index, args.model).text())
    print(f"\n| queries | hits from | mean P@{args.k} | actions at >= 0.9 | at >= 0.8 | "
          "below 0.8 |")
    print("|---|---|---|---|---|---|")
    for qfile in args.queries:
        asked = read_queries(None if qfile == "fixed" else qfile)
        for grounded in (False, True):
            precision = []
            for action, query in asked:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")   # "the analysis sees no take that ..."
                    hits = ml.search(query, index, k=4 * args.k, grounded=grounded)
                best = list(dict.fromkeys(h.file for h in hits))[:args.k]
                precision.append(float(np.mean([labels[Path(f).name] == action
                                                for f in best])) if best else 0.0)
            actions = [a for a, _ in asked]
            per = {a: float(np.mean([p for b, p in zip(actions, precision) if b == a]))
                   for a in dict.fromkeys(actions)}
            low = ", ".join(f"{a} {p:.2f}" for a, p in per.items() if p < 0.8)
            print(f"| {Path(qfile).name} | "
                  f"{'model and analysis' if grounded else 'model'} | "
                  f"{np.mean(precision):.3f} | {sum(p >= 0.9 for p in per.values())} | "
                  f"{sum(p >= 0.8 for p in per.values())} | {low} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Search a real library by what the body does: the analysis stored in the index against the
learned model alone, on queries in plain words for actions only the analysis can see and for
walking, running and jumping.

    # a library of cmu_dev, both Bandai archives, CMU 49 and the DeepMimic clips, as a user
    # would lay it out (copies of the folders, made of symlinks: cp -rs), then
    OMP_NUM_THREADS=1 .venv/bin/motionlang index /tmp/lib -o /tmp/lib.idx
    OMP_NUM_THREADS=1 .venv/bin/python experiments/grounded_search.py /tmp/lib.idx \\
        [--trials ../shared/data/cmu_dev/trials.tsv] [--k 5] [--show]

What each take shows comes from what its makers wrote, never from the analysis: Bandai's
file names (its content labels), CMU's descriptions of the cmu_dev trials (``trials.tsv``),
the DeepMimic clips' names, CMU 49's trials 18-20 (balancing on one leg). A hit is right
when its take is labelled with the query's action; an action no take is labelled with is
listed with its hits (and their reasons) to be looked at, not scored. Prints a table per
query and the mean precision@k over actions, both ways. Bandai data: CC BY-NC.
"""
from __future__ import annotations

import argparse
import csv
import re
import warnings
from collections import defaultdict
from pathlib import Path

from motionlang.library.search import Library

#: queries in plain words, per action (written for this script; none is a training caption)
QUERIES = {
    "sit": ["someone sits down", "a person takes a seat"],
    "crouch": ["a person crouches down low", "somebody squats"],
    "climb": ["a person climbs up", "someone clambers up onto something"],
    "kneel": ["a person kneels on the floor", "someone gets down on one knee"],
    "lie": ["someone lies on the ground", "a person lying on their back"],
    "balance": ["a person balances on one leg", "someone standing on one foot"],
    "kick": ["a person kicks", "someone kicking with the leg"],
    "punch": ["a person punches", "someone throws a punch"],
    "crawl": ["a person crawls on all fours", "someone crawling"],
    "walk": ["a person walks", "someone strolling along"],
    "run": ["a person runs", "somebody jogging"],
    "jump": ["a person jumps", "someone leaps into the air"],
}
#: Bandai content label -> actions it shows
BANDAI = {"bow": {"bow"}, "bye": {"wave"}, "byebye": {"wave"}, "dash": {"run"},
          "kick": {"kick"}, "punch": {"punch"}, "run": {"run"}, "walk": {"walk"},
          "walk-back": {"walk"}, "walk-left": {"walk"}, "walk-right": {"walk"},
          "walk-turn-left": {"walk", "turn"}, "walk-turn-right": {"walk", "turn"},
          "raise-up-both-hands": {"raise"}, "raise-up-left-hand": {"raise"},
          "raise-up-right-hand": {"raise"}, "wave-both-hands": {"wave"},
          "wave-left-hand": {"wave"}, "wave-right-hand": {"wave"}}
#: DeepMimic clip name -> actions
DEEPMIMIC = {"walk": {"walk"}, "run": {"run"}, "jump": {"jump"}, "kick": {"kick"},
             "spinkick": {"kick", "spin"}, "punch": {"punch"}, "crawl": {"crawl"},
             "getup_facedown": {"lie"}, "getup_faceup": {"lie"}, "roll": {"roll"},
             "cartwheel": {"cartwheel"}, "backflip": {"flip"}, "spin": {"spin"},
             "dance_a": {"dance"}, "dance_b": {"dance"}}
#: words of CMU's descriptions -> actions
CMU_WORDS = {"walk": "walk", "stride": "walk", "jump": "jump", "run": "run", "jog": "run",
             "kick": "kick", "punch": "punch", "climb": "climb", "sit": "sit",
             "balance": "balance", "crawl": "crawl", "kneel": "kneel", "squat": "crouch",
             "jete": "jump", "leap": "jump", "pirouette": "spin"}   # a jete is a leap


def truth(path: str, described: dict[str, str]) -> set[str]:
    """The actions a take is labelled with by its makers (module docstring)."""
    name = Path(path.split("#")[0]).stem
    m = re.match(r"dataset-\d_(.+?)_[a-z]+_\d+$", name)
    if m:
        return set(BANDAI.get(m.group(1), set()))
    if name.startswith("humanoid3d_"):
        return set(DEEPMIMIC.get(name[len("humanoid3d_"):], set()))
    if name in ("49_18", "49_19", "49_20"):
        return {"balance"}
    words = described.get(name, "")
    return {a for w, a in CMU_WORDS.items() if re.search(rf"\b{w}", words)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("index")
    ap.add_argument("--trials", default="../shared/data/cmu_dev/trials.tsv")
    ap.add_argument("--k", type=int, default=5)
    ap.add_argument("--show", action="store_true", help="print every hit with its reason")
    args = ap.parse_args()
    described = {}
    if Path(args.trials).is_file():
        with open(args.trials, newline="") as fh:
            described = {r["trial"]: r["cmu_description"] for r in
                         csv.DictReader(fh, delimiter="\t")}
    lib = Library.open(args.index)
    labels = [truth(e.name, described) for e in lib.data.entries]
    held = defaultdict(int)
    for s in labels:
        for a in s:
            held[a] += 1
    of_take = {e.name: labels[i] for i, e in enumerate(lib.data.entries)}
    print(f"{args.index}: {len(labels)} takes; labelled: "
          + ", ".join(f"{a} {n}" for a, n in sorted(held.items())))
    per_action: dict[str, dict[bool, list[float]]] = defaultdict(lambda: {True: [], False: []})
    print(f"\n{'query':44s} {'takes':>5s}  P@{args.k} grounded  P@{args.k} learned  "
          "first hit (grounded)")
    found = {True: 0, False: 0}
    askable = 0
    for action, queries in QUERIES.items():
        for q in queries:
            row = {}
            for grounded in (True, False):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    hits = lib.search(q, k=args.k, grounded=grounded)
                right = [action in of_take[h.file] for h in hits]
                row[grounded] = (sum(right) / args.k, hits)
                if held[action]:
                    per_action[action][grounded].append(sum(right) / args.k)
            if held[action]:
                askable += 1
                for g in (True, False):
                    found[g] += any(action in of_take[h.file] for h in row[g][1])
            first = row[True][1][0] if row[True][1] else None
            said = "-" if first is None else f"{first.file} ({first.why or 'learned'})"
            scored = held[action] > 0
            print(f"{q:44s} {held[action]:5d}  {row[True][0] if scored else float('nan'):11.2f}"
                  f"  {row[False][0] if scored else float('nan'):10.2f}  {said[:90]}")
            if args.show:
                for h in row[True][1]:
                    print(f"{'':6s}{h.line(0)[5:]}  labelled {sorted(of_take[h.file])}")
    print(f"\nqueries with a labelled take in the top {args.k}: grounded {found[True]} of "
          f"{askable}, learned alone {found[False]} of {askable}")
    for grounded in (True, False):
        scored = {a: sum(v[grounded]) / len(v[grounded]) for a, v in per_action.items()}
        only = [a for a in scored if a not in ("walk", "run", "jump")]
        gait = [a for a in scored if a in ("walk", "run", "jump")]
        print(f"\n{'grounded' if grounded else 'learned alone'}: mean P@{args.k} over "
              f"{', '.join(only)}: {sum(scored[a] for a in only) / max(1, len(only)):.2f}; "
              f"over {', '.join(gait)}: {sum(scored[a] for a in gait) / max(1, len(gait)):.2f}")


if __name__ == "__main__":
    main()

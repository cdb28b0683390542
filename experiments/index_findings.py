"""What an index's stored findings show for the takes whose paths hold a word: for each
group (the word, and the folder's first part), how many takes have a finding of each of
the labels asked, in every combination.

    .venv/bin/python experiments/index_findings.py /tmp/lib.idx --match wave bye \\
        --labels wave raise
"""
from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("index", type=Path)
    ap.add_argument("--match", nargs="+", required=True, help="words of the takes' paths")
    ap.add_argument("--labels", nargs="+", required=True, help="finding labels to count")
    args = ap.parse_args()
    from motionlang.library.store import load_index

    data = load_index(args.index)
    counts: Counter[tuple[str, tuple[bool, ...]]] = Counter()
    for e in data.entries:
        word = next((w for w in args.match if w in e.path), None)
        if word is None:
            continue
        labels = {f["label"] for f in e.findings or ()}
        group = f"{e.path.split('/')[0]} {word}"
        counts[(group, tuple(lab in labels for lab in args.labels))] += 1
    print("group\ttakes\t" + "\t".join(args.labels))
    for (group, shown), n in sorted(counts.items()):
        print(f"{group}\t{n}\t" + "\t".join("yes" if s else "-" for s in shown))


if __name__ == "__main__":
    main()

"""Which of KIT-ML's real annotations the phrase table in other words
(``analysis.words.PARAPHRASES``) reads, and as what: to read through by eye for phrases
that name an action the sentence does not.

    .venv/bin/python experiments/paraphrases_kitml.py \\
        [--annotations ../shared/data/kitml/annotations_tmr.json]

Prints one line per distinct annotation a phrase matches (the action, the words matched,
the sentence) and the count; the mirrored copies (ids starting with ``M``) are left out.
"""
from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path

from motionlang.analysis.words import PARAPHRASES


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--annotations", default="../shared/data/kitml/annotations_tmr.json")
    args = ap.parse_args(argv)
    data = json.loads(Path(args.annotations).read_text(encoding="utf-8"))
    texts = sorted({a["text"] for key, v in data.items() if not key.startswith("M")
                    for a in v["annotations"]})
    read: Counter[str] = Counter()
    for text in texts:
        low = " ".join(text.lower().split())
        for pattern, action in PARAPHRASES:
            m = pattern.search(low)
            if m:
                read[action] += 1
                print(f"{action}\t{m.group(0)!r}\t{text}")
    print(f"\n{sum(read.values())} readings in {len(texts)} distinct annotations: "
          + ", ".join(f"{a} {n}" for a, n in read.most_common()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

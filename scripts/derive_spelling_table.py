"""Derive the word-level correction table shipped in ``motionlang/data/spelling_corrections.tsv``.

Input: KIT-ML's ``sentences_corrections.tsv`` (original sentence TAB normalised sentence,
from kit-mld-ke). Each original is tokenised without corrections
(``motionlang.datasets.text.base_tokens``) and aligned word by word with its normalised
version (difflib). Every aligned substitution ``wrong -> right`` (one word to one or more
words, or to nothing) is counted; a word enters the table when it is replaced more often than
it is kept, by its most frequent replacement, unless it is in ``EXCLUDE`` (below).

Usage::

    python scripts/derive_spelling_table.py ../shared/data/kitml/sentences_corrections.tsv \
        src/motionlang/data/spelling_corrections.tsv
"""
from __future__ import annotations

import argparse
import difflib
import sys
from collections import Counter, defaultdict
from pathlib import Path

from motionlang.datasets.text import base_tokens, normalize
from motionlang.utils.atomic import atomic_write

# The reference column was made by a spell checker that sometimes replaced a word by a
# different, wrong one ("leftwards" -> "leotards", "trunk" -> "turn", "spining" ->
# "shining"). Copying those would damage new text, so these source words are left alone.
EXCLUDE = frozenset("""
backstep baskeball buched feelering flopper fowards gitarre guitarre leftwards mingolf
podest puch schich spining sth stiring streight strid trunk walds walzer wavs whiping wipping
""".split())


def read_pairs(path: Path) -> list[tuple[str, str]]:
    pairs = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if "\t" in line:
            a, b = line.split("\t", 1)
            pairs.append((a.strip(), b.strip()))
    return pairs


def derive(pairs: list[tuple[str, str]]) -> dict[str, str]:
    subs: dict[str, Counter] = defaultdict(Counter)
    kept: Counter = Counter()
    for orig, ref in pairs:
        a, b = base_tokens(orig), ref.split()
        sm = difflib.SequenceMatcher(a=a, b=b, autojunk=False)
        for op, i1, i2, j1, j2 in sm.get_opcodes():
            if op == "equal":
                kept.update(a[i1:i2])
            elif op == "replace" and i2 - i1 == j2 - j1:
                for w, r in zip(a[i1:i2], b[j1:j2]):
                    subs[w][r] += 1
            elif op == "replace" and i2 - i1 == 1:      # one word -> several ("1m" -> ...)
                subs[a[i1]][" ".join(b[j1:j2])] += 1
            elif op == "delete" and i2 - i1 == 1:       # a word the reference drops
                subs[a[i1]][""] += 1
    table = {}
    for w, c in subs.items():
        rep, n = c.most_common(1)[0]
        # Number tokens are never rewritten (their context decides); "" needs a majority
        # of at least 2 so a one-off rewording does not delete a word everywhere.
        if n > kept[w] and not w.isdigit() and (rep or n >= 2) and w not in EXCLUDE:
            table[w] = rep
    return table


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tsv", type=Path)
    ap.add_argument("out", type=Path)
    args = ap.parse_args(argv)
    pairs = read_pairs(args.tsv)
    table = derive(pairs)
    with atomic_write(args.out) as fh:
        fh.write(f"# derived from {args.tsv.name} ({len(pairs)} sentences) by "
                 "scripts/derive_spelling_table.py; wrong<TAB>right\n")
        for w in sorted(table):
            fh.write(f"{w}\t{table[w]}\n")
    hits = sum(normalize(a, table) == b for a, b in pairs)
    print(f"{len(table)} entries; normalize() reproduces {hits}/{len(pairs)} "
          f"= {100 * hits / len(pairs):.1f}% of the normalised sentences", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Which true actions the round trip's descriptions name, by their place in the motion.

Reads a report written by ``motionlang evaluate --l2m ... -o REPORT.json`` on a procedural
corpus and prints, for the L2M's round trip and its nearest-neighbour baseline, how often the
first, the later and the only action of a motion is named (``evaluation.seq2seq
.actions_named``). ``evaluate`` prints the same line for new reports; this script reads
older ones.

    python scripts/round_trip_actions.py report.json --data corpus
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def main(argv=None) -> int:
    from motionlang.cli.seq2seq_commands import named_line
    from motionlang.datasets.synth import ground_truth
    from motionlang.evaluation.seq2seq import actions_named

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("report", help="JSON report of motionlang evaluate --l2m")
    ap.add_argument("--data", required=True, help="the procedural corpus it was made on")
    args = ap.parse_args(argv)
    report = json.loads(Path(args.report).read_text())
    for key, name in (("l2m_round_trip", "L2M round trip"),
                      ("nn_round_trip", "nearest training sentence, round trip")):
        if key not in report:
            continue
        descriptions = report[key]["descriptions"]
        truths = {}
        for i in {d[0] for d in descriptions}:
            meta = Path(args.data) / f"{i}_meta.json"
            if not meta.exists():
                print(f"{meta}: missing; is --data the corpus of this report?", file=sys.stderr)
                return 2
            truths[i] = ground_truth(json.loads(meta.read_text()))
        print(f"{name}, true actions named: {named_line(actions_named(descriptions, truths))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

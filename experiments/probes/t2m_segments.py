"""Which actions a text-to-motion model gets wrong in the order check, per true action.

``motionlang evaluate-t2m`` gives one figure for the first and one for the later segments
of the compositional test sentences; this prints them per true action, and the commonest
wrong labels (``evaluation.action_order.segment_tally``). Needs a procedural corpus.

    python experiments/probes/t2m_segments.py --data corpus --model ts.pt [--split test]
"""
from __future__ import annotations

import argparse
import sys


def main(argv=None) -> int:
    import torch

    import motionlang as ml
    from motionlang.datasets.position_items import build_twostream_data
    from motionlang.evaluation.action_order import segment_labels, segment_tally
    from motionlang.evaluation.t2m.compare import eval_items, fit_prototypes, positions_to_features

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="the procedural corpus trained on")
    ap.add_argument("--model", required=True, help="two-stream or L2M checkpoint")
    ap.add_argument("--split", default="test")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    data = build_twostream_data(args.data)
    protos = fit_prototypes(data)
    if protos is None:
        print(f"{args.data}: no ground-truth segments (not a procedural corpus)",
              file=sys.stderr)
        return 2
    items = [it for it in eval_items(data, args.split) if it.compositional]
    t2m = ml.text_to_motion(args.model)
    pred = [segment_labels(positions_to_features(data.features, t2m.positions21(
        it.sentence, len(it.target))), it.ranges, protos) for it in items]
    right, confusions = segment_tally(pred, [it.truth for it in items])
    print(f"{len(items)} compositional {args.split} sentences; segments labelled right:")
    for action in sorted({a for _, a in right}):
        cells = [f"{place} {right[place, action][0]}/{right[place, action][1]}"
                 if (place, action) in right else f"{place} -" for place in ("first", "later")]
        print(f"  {action:12s} " + "   ".join(cells))
    common = sorted(confusions.items(), key=lambda kv: (-kv[1], kv[0]))[:10]
    print("commonest wrong labels (true -> label: count): " +
          ", ".join(f"{a} -> {b}: {n}" for (a, b), n in common))
    return 0


if __name__ == "__main__":
    sys.exit(main())

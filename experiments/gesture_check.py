"""Does a text-to-motion model do the gesture it is asked for? Procedural test motions of one
action each (docs/results/real-motion.md, eighth session).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/gesture_check.py CORPUS \
        [--model l2m] [--model l2m-procedural] [--splits RUN/splits] [--per-action 12]

CORPUS is a procedural corpus (``motionlang data synth --out CORPUS --n 6000 --seed 0``, as
``scripts/train_shipped_models.sh`` makes it). From its test split (``--splits``, else the
split ``train`` makes with seed 0), up to ``--per-action`` motions whose metadata holds a
single action among those below. Each model generates one motion from the motion's first
sentence at its length (as ``motionlang evaluate-judge`` does: the model's own decoding,
feet locked as ``generate`` writes them), and the real and generated motions are measured
on the 21-joint body at 12.5 Hz:

- wave, raise_arms: how high the named wrist rises above the root (m; both wrists for
  "both": the lower of the two);
- kick, stomp: how high the named toe rises above the floor (m);
- jump: the root's rise over its height in the first frame (m);
- squat: the root's drop under its height in the first frame (m).

A motion "does it" when its figure reaches half the real motion's. Prints, per action, the
real and generated means and the share done. The procedural corpus is this project's own
(MIT); the packaged ``l2m`` is trained on Bandai data too (CC BY-NC 4.0).
"""
from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

ACTIONS = ("wave", "raise_arms", "kick", "stomp", "jump", "squat")


def measure(p: np.ndarray, action: str, side: str | None) -> float:
    """The action's figure (module docstring) of 21-joint positions (T, 21, 3), metres."""
    from motionlang.features.joint_map import KIT21_NAMES
    i = KIT21_NAMES.index
    root = p[:, 0, 1]
    sides = ("L", "R") if side in (None, "both") else (side[0].upper(),)
    if action in ("wave", "raise_arms"):
        return float(min((p[:, i(s + "W"), 1] - root).max() for s in sides))
    if action in ("kick", "stomp"):
        return float(min(p[:, i(s + "F"), 1].max() for s in sides))
    if action == "jump":
        return float(root.max() - root[0])
    if action == "squat":
        return float(root[0] - root.min())
    raise ValueError(action)


def _fail(message: str) -> None:
    """Bad input: one line on stderr, exit 2."""
    print(f"gesture_check: {message}", file=sys.stderr)
    sys.exit(2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("corpus", type=Path)
    ap.add_argument("--model", action="append", help="packaged name or file (repeat)")
    ap.add_argument("--splits", type=Path, help="a run's splits folder (test.txt)")
    ap.add_argument("--per-action", type=int, default=12)
    args = ap.parse_args()

    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.datasets.splits import load_splits, random_split
    from motionlang.models.t2m import FPS

    ids = sorted(f.name[:-len("_meta.json")] for f in args.corpus.glob("*_meta.json"))
    if not ids:
        _fail(f"{args.corpus}: no procedural corpus there (no *_meta.json; make one with "
              "motionlang data synth)")
    test = (load_splits(args.splits)["test"] if args.splits
            else random_split(ids, seed=0)["test"])
    picked: dict[str, list] = defaultdict(list)
    for mid in test:
        if not (args.corpus / f"{mid}_meta.json").is_file():   # a mixed run's other data
            continue
        meta = json.loads((args.corpus / f"{mid}_meta.json").read_text())
        prims = meta["primitives"]
        if len(prims) != 1 or prims[0]["action"] not in ACTIONS:
            continue
        a = prims[0]["action"]
        if len(picked[a]) >= args.per_action:
            continue
        text = json.loads((args.corpus / f"{mid}_annotations.json").read_text())[0]
        p = np.asarray(ml.body21(args.corpus / f"{mid}_mmm.xml"))
        step = max(1, int(round(meta["fps"] / FPS)))
        picked[a].append((text, p[::step], prims[0].get("side")))
    if not picked:
        _fail(f"{args.corpus}: no test motion of one action among {', '.join(ACTIONS)}")
    models = args.model or ["l2m"]
    rows = {a: {"real": [measure(p, a, s) for _, p, s in items]} for a, items in picked.items()}
    for name in models:
        t2m = ml.text_to_motion(name)
        for a, items in picked.items():
            rows[a][name] = [measure(t2m.positions21(text, len(p), foot_lock=True), a, s)
                             for text, p, s in items]
    print(f"{sum(len(v) for v in picked.values())} procedural test motions of one action "
          f"each ({args.corpus}); figure in metres (module docstring), share of motions "
          "reaching half the real motion's\n")
    print("| action | motions | real | " + " | ".join(models) + " |")
    print("|---|---|---|" + "---|" * len(models))
    done_all = defaultdict(list)
    for a in ACTIONS:
        if a not in rows:
            continue
        real = np.array(rows[a]["real"])
        cells = []
        for name in models:
            gen = np.array(rows[a][name])
            done = gen >= 0.5 * real
            done_all[name].extend(done.tolist())
            cells.append(f"{gen.mean():.2f} ({100 * done.mean():.0f} % done)")
        print(f"| {a} | {len(real)} | {real.mean():.2f} | " + " | ".join(cells) + " |")
    print("| all | " + str(sum(len(v) for v in picked.values())) + " | | " +
          " | ".join(f"{100 * np.mean(done_all[n]):.0f} % done" for n in models) + " |")


if __name__ == "__main__":
    main()

"""Train the real-motion judge (``models.judge``) on the Bandai Namco training takes and
print its content and style accuracy on the held-out test takes (dataset 2, take numbers
0 mod 5), with the ground truth's physical measures beside them.

    MOTIONLANG_CACHE=/tmp/cache OMP_NUM_THREADS=1 .venv/bin/python experiments/bandai_judge.py \
        [--data ../shared/data/bandai] [--epochs 30] [--out judge.pt] [--no-mirror] [--cross]
        [--primitives CORPUS] [--runs DIR]

Validation takes (4 mod 5) pick the epoch. Accuracy is over the judge's every label (25
contents, 19 styles) and, in brackets, among dataset 2's own (10 contents, 7 styles), the
only labels test takes have. Test takes come from the same actors and sessions as the
training takes (the data has no actor ids), so ``--cross`` also trains a judge on dataset 2
alone and scores it on dataset 1's walks and runs (another recording, other performances),
styles mapped onto dataset 2's where one matches (old -> elderly, tired -> exhausted, ...).
``--primitives``: a procedural corpus (``motionlang data synth``) whose primitives that
show a Bandai action join the training takes (content only, no style).
The judge is trained on Bandai data: CC BY-NC 4.0, non-commercial use only.
"""
from __future__ import annotations

import argparse
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: dataset 1 styles -> the dataset 2 style of the same meaning
SAME_STYLE = {"normal": "normal", "feminine": "feminine", "active": "active", "old": "elderly",
              "tired": "exhausted", "masculinity": "masculine", "childish": "youthful"}


def restricted_accuracy(probs: np.ndarray, names: list[str], allowed: set[str],
                        truth: list[str]) -> float:
    """Accuracy when the judge may only answer with labels in ``allowed``."""
    keep = np.array([n in allowed for n in names])
    pick = np.where(keep[None], probs, -1.0).argmax(-1)
    return float(np.mean([names[i] == t for i, t in zip(pick, truth)]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    ap.add_argument("--epochs", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-mirror", dest="mirror", action="store_false",
                    help="train without left/right mirrored copies")
    ap.add_argument("--out", type=Path, help="save the judge here (kind 'judge')")
    ap.add_argument("--primitives", type=Path, metavar="CORPUS",
                    help="also train on this procedural corpus' primitives")
    ap.add_argument("--cross", action="store_true",
                    help="also: train on dataset 2 only, test on dataset 1's walks and runs")
    ap.add_argument("--runs", type=Path, help="the trainer's run folders (default: a temporary "
                                              "folder)")
    args = ap.parse_args()

    import torch

    from motionlang.evaluation.judge import judge_motions
    from motionlang.models.judge.fit import (
        accuracy,
        bandai_items,
        median_bones,
        primitive_items,
    )
    from motionlang.recipes.judge import train_on_items
    torch.set_num_threads(1)
    args.runs = args.runs or Path(tempfile.mkdtemp(prefix="bandai_judge_"))
    t0 = time.time()
    train, val, test = (bandai_items(args.data, s) for s in ("train", "val", "test"))
    extra = primitive_items(args.primitives) if args.primitives else []
    print(f"takes: train {len(train)}, val {len(val)}, test {len(test)}; procedural "
          f"primitives {len(extra)} (read in {time.time() - t0:.0f} s)", flush=True)
    t1 = time.time()
    # the real actors' body, not a median with the procedural primitives' (as train judge)
    judge, _ = train_on_items(train + extra, val, {"bones": median_bones(train or extra)},
                              train_config(args, "main"), mirror=args.mirror,
                              log=lambda s: print(s, flush=True))
    fit_s = time.time() - t1
    if args.out:
        judge.save(args.out)
    acc = accuracy(judge, test)
    got = judge.judge([it.positions for it in test], test[0].fps)
    c2 = restricted_accuracy(got["content"], judge.config.contents,
                             {it.content for it in test}, [it.content for it in test])
    s2 = restricted_accuracy(got["style"], judge.config.styles, {it.style for it in test},
                             [it.style for it in test])
    print(f"\ntest takes: {acc['n']}; content accuracy {acc['content']:.3f} ({c2:.3f} among "
          f"dataset 2's contents), style accuracy {acc['style']:.3f} ({s2:.3f} among its "
          f"styles); validation-picked of {args.epochs} epochs, {fit_s / 60:.1f} min training")
    names = judge.config.contents
    wrong = Counter((it.content, names[int(i)]) for it, i in
                    zip(test, got["content"].argmax(-1)) if names[int(i)] != it.content)
    print("most common content confusions (truth -> judged):",
          ", ".join(f"{a} -> {b} x{n}" for (a, b), n in wrong.most_common(5)) or "none")
    for label in ("content", "style"):
        per = {}
        for it, i in zip(test, got[label].argmax(-1)):
            truth = getattr(it, label)
            ok, n = per.get(truth, (0, 0))
            per[truth] = (ok + (getattr(judge.config, label + "s")[int(i)] == truth), n + 1)
        print(f"per {label}:", ", ".join(f"{k} {ok / n:.2f}" for k, (ok, n) in sorted(per.items())))
    truth = judge_motions(judge, [it.positions for it in test], test[0].fps,
                          [(it.content, it.style) for it in test])
    print(f"ground truth at {test[0].fps} Hz: skating {truth['skating']:.3f} m/s, penetration "
          f"{truth['penetration'] * 100:.2f} cm (max {truth['penetration_max'] * 100:.1f} cm), "
          f"largest one-frame root move {truth['root_jump'] * 100:.1f} cm "
          f"(mean per take {truth['root_jump_mean'] * 100:.1f} cm), diversity "
          f"{truth['diversity']:.2f}")
    if args.cross:
        cross(train, val, args)
    print(f"total {(time.time() - t0) / 60:.1f} min")


def train_config(args, name: str):
    """``train judge``'s trainer settings, with this script's epochs and seed, run folder
    ``args.runs / name``."""
    from motionlang.recipes.judge import JUDGE
    from motionlang.training.config import TrainConfig
    return TrainConfig(**{**JUDGE.train_defaults, "epochs": args.epochs, "seed": args.seed,
                          "out_dir": str(args.runs / name)})


def cross(train, val, args) -> None:
    """A judge trained on dataset 2 alone, scored on dataset 1's walk and run takes."""
    from dataclasses import replace

    from motionlang.models.judge.fit import accuracy
    from motionlang.recipes.judge import train_on_items
    two = [it for it in train if it.id.startswith("dataset-2")]
    one = [replace(it, style=SAME_STYLE.get(it.style)) for it in train
           if it.id.startswith("dataset-1") and it.content in ("walk", "run")]
    judge, _ = train_on_items(two, val, {}, train_config(args, "cross"), mirror=args.mirror)
    acc = accuracy(judge, one)
    print(f"\ncross-dataset: trained on dataset 2 ({len(two)} takes), tested on dataset 1's "
          f"{acc['n']} walks and runs: content {acc['content']:.3f}, style {acc['style']:.3f} "
          f"(over the {sum(it.style is not None for it in one)} with a matching style)")
    for it, (c, s) in zip(one, judge.predict([it.positions for it in one], one[0].fps)):
        if c != it.content or (it.style and s != it.style):
            print(f"  {it.id}: judged {c} / {s}")


if __name__ == "__main__":
    main()

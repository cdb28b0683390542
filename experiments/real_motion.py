"""How `describe` names the action of real motion from another lab (issue #41).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/real_motion.py [--model m2l ...]
        [--data ../shared/data] [--cmudev /tmp/cmudev] [-o rows.tsv] [--raw]

Motions: the 59 files of ``cmu_dev`` (56 CMU trials of subjects 05, 06, 08, 12, 13 in the
iClone, Second-Life and MakeHuman rigs; extracted from ``cmu_dev/cmu-dev.tar.xz`` to
``--cmudev``, extracted there first if absent), the 33 trials of CMU subject 35
(``cmu35WalkJog.mat``: 23 walks, 10 jogs), the raw ``35_01.amc``, the three raw CMU 49 trials
and KIT 00001. Each file's *asked action* comes from CMU's own description
(``walk``-words -> walk, ``jump`` -> jump, ``run``/``jog`` -> run, ``dribble``, ``dance``);
its *said action* from the top sentence's words (:func:`said_action`).

Printed: per asked action, how often the top sentence names it; the same first action across
rigs for the trials that come in several rigs; sentences without a verb (never allowed); and
the constant sentence "a person walks forward" as the baseline the issue compares with.
"""
from __future__ import annotations

import argparse
import csv
import sys
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

# A sentence's action: the first of these word sets its words hit, in this order (a jump
# described as "jumps forward and walks back" is a jump; "runs" wins over "walks" for the
# same reason: the rarer, more specific verb is the main action).
ACTION_WORDS = (
    ("jump", {"jump", "jumps", "jumping", "jumped", "hop", "hops", "hopping", "leap",
              "leaps", "leaping", "jete", "jetes"}),
    ("run", {"run", "runs", "running", "ran", "jog", "jogs", "jogging", "dash", "dashes",
             "dashing", "sprint", "sprints", "sprinting"}),
    ("dribble", {"dribble", "dribbles", "dribbling", "basketball"}),
    ("dance", {"dance", "dances", "dancing", "pirouette", "pirouettes", "ballet", "twirl",
               "twirls", "spins", "spin", "spinning"}),
    ("walk", {"walk", "walks", "walking", "walked", "stroll", "strolls", "strolling",
              "steps", "step", "stepping", "stride", "strides", "march", "marches"}),
)
UNFAMILIAR = "unfamiliar"


def said_action(text: str) -> str:
    """The action a sentence names (``ACTION_WORDS``), ``"unfamiliar"`` when it says it does
    not know, else ``"other"``."""
    words = set(text.lower().replace(",", " ").replace(".", " ").split())
    if "unfamiliar" in words:
        return UNFAMILIAR
    for action, ws in ACTION_WORDS:
        if words & ws:
            return action
    return "other"


def asked_action(description: str) -> str:
    """The main action of a CMU description ("walk", "forward jump", "basketball - forward
    dribble", "dance - small jetes, pirouette", "jump up to grab, reach for, tiptoe")."""
    d = description.lower()
    if d.startswith("dance"):
        return "dance"
    if "dribble" in d:
        return "dribble"
    if "jump" in d:
        return "jump"
    if "run" in d or "jog" in d:
        return "run"
    if "walk" in d:
        return "walk"
    return "other"


def has_verb(text: str) -> bool:
    from motionlang.models.seq2seq.decode.grounded import has_verb as verb
    return verb(text)


def motions(data: Path, cmudev: Path):
    """``(name, trial, rig, asked, Motion or path)`` for every measured motion."""
    from motionlang.datasets.named import cmu35_walkjog, cmu_dev_folder
    cmu_dev_folder(data, cmudev)
    with open(data / "cmu_dev" / "trials.tsv", newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            yield (row["file"], row["trial"], row["rig"], asked_action(row["cmu_description"]),
                   cmudev / "cmu-dev" / row["file"])
    for t in cmu35_walkjog(data).trials:
        yield (f"cmu35/{t.trial}", t.trial, "cmu35-mat", "run" if t.label == "jog" else "walk",
               t.motion)
    yield "cmu35/35_01.amc", "35_01", "amc", "walk", data / "cmu35" / "35_01.amc"
    for p in sorted((data / "cmu49").glob("*.amc")):
        yield f"cmu49/{p.name}", p.stem, "amc", "other", p
    yield "kitml/00001_mmm.xml", "kit00001", "mmm", "walk", data / "kitml" / "00001_mmm.xml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", action="append", help="describing models (default: m2l and "
                    "m2l-procedural)")
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--cmudev", default="/tmp/cmudev")
    ap.add_argument("-w", "--width", type=int, default=5)
    ap.add_argument("-o", "--out", help="write one row per motion and model (TSV)")
    ap.add_argument("--raw", action="store_true", help="the models' beams as they are "
                    "(describe --raw), without the gait check")
    args = ap.parse_args()

    import torch

    import motionlang as ml
    torch.set_num_threads(1)
    items = list(motions(Path(args.data), Path(args.cmudev)))
    rows = []
    for spec in args.model or ["m2l", "m2l-procedural"]:
        model = ml.load_model(spec)
        hits: dict[str, list[int]] = defaultdict(lambda: [0, 0])
        const: dict[str, list[int]] = defaultdict(lambda: [0, 0])
        first: dict[str, dict[str, str]] = defaultdict(dict)
        verbless = []
        print(f"== {spec}")
        for name, trial, rig, asked, src in items:
            try:
                text = ml.describe(src, model, args.width, raw=args.raw)[0][0]
            except Exception as e:  # a motion no reader takes counts as missed, and is shown
                text = f"ERROR {e}"
            said = said_action(text)
            first[trial][rig] = said
            if not text.startswith("ERROR") and not has_verb(text):
                verbless.append((name, text))
            if asked != "other":
                hits[asked][0] += said == asked
                hits[asked][1] += 1
                const[asked][0] += asked == "walk"
                const[asked][1] += 1
            ok = "" if asked in ("other", said) else f"  MISSED ({asked})"
            print(f"{name}: {text}{ok}")
            rows.append((spec, name, rig, asked, said, text))
        print(f"-- {spec}: action named (model / constant 'a person walks forward')")
        total = [0, 0, 0]
        for a in sorted(hits):
            h, n = hits[a]
            total[0] += h
            total[1] += n
            total[2] += const[a][0]
            print(f"   {a:8s} {h:3d}/{n:3d} = {100 * h / n:5.1f} %   constant {const[a][0]}/{n}")
        print(f"   all      {total[0]:3d}/{total[1]:3d} = {100 * total[0] / total[1]:5.1f} %   "
              f"constant {100 * total[2] / total[1]:.1f} %")
        multi = {t: r for t, r in first.items() if len(r) > 1}
        same = sum(len(set(r.values())) == 1 for r in multi.values())
        print(f"   same first action across rigs: {same}/{len(multi)} "
              f"{ {t: r for t, r in multi.items()} }")
        print(f"   sentences without a verb: {len(verbless)} {verbless[:5]}")
        counts = Counter(said for s, _, _, _, said, _ in rows if s == spec)
        print(f"   said: {dict(counts)}")
    if args.out:
        with open(args.out, "w", newline="") as f:
            w = csv.writer(f, delimiter="\t")
            w.writerow(["model", "file", "rig", "asked", "said", "text"])
            w.writerows(rows)


if __name__ == "__main__":
    main()

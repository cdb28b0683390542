"""The packaged two-stream recipe (``scripts/train_shipped_models.sh``) trained in parts,
one part per session, on a fresh checkout: run folders are not kept between sessions, so
each part starts from a state committed to the repository and ends by replacing it.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/twostream_parts.py PART
        [--data SOURCE ...] [--threads 1] [--full-state] [--save-only]
        [--select-evaluator EVALUATOR --select-data SOURCE]

The package's data and selection: ``--data bandai:../shared/data/bandai@1
--select-evaluator runs/evaluator_bandai --select-data bandai:../shared/data/bandai`` (the
corpus then gets ``@1`` too: half of each epoch each; the evaluator from ``motionlang
train evaluator --data bandai:... --epochs 10``). Give the same options to every part.

The recipe is a table of phases (``PHASES``: the epoch a phase ends at, its learning rate,
and how many of its last epochs decay the rate), one part each. Each part fits in about two
hours on one core of the 2-core machine: an epoch of the package's data takes 11-13 minutes,
the data preparation about 10 more. Part 1 starts the run; part N continues from the state
the part before committed, in ``experiments/state/twostream_recipe/``
(``training.run_state``: the trainer's ``last.pt`` with the optimiser's moments and the RNG
states, ``run.json``, ``splits/``, ``history.json``, ``commands.jsonl``, ``state.json``;
about 37 MB at h = 128, and so by default stored compact: ``save_state(compact=True)``,
``last.pt.xz`` with the weights in float16 and the moments in bfloat16, about 14 MB, small
enough to commit beside the package; ``--full-state`` keeps it exact). The last part also
puts ``model.pt`` there. With ``--full-state`` the parts give the model of one uninterrupted
run bit for bit (``tests/test_run_state.py``). A part rebuilds the corpus (``data synth``,
seed 0) and the features from it first (minutes; the features through the on-disk cache)
and checks them against the saved split and normaliser. Printed at the end: what to commit.
A compact state resumes the run up to the rounding of its weights and moments
(``training.run_state``). Run a part again after an interruption in the same session: it
continues from the run folder's own ``last.pt`` (checkpoints every 50 steps). A part that a
session's end would cut short: stop it, ``PART --save-only`` saves where it stopped (the
last checkpoint) as the state to commit, and the next session runs the same PART again to
finish it.

``--select-evaluator`` scores every epoch's motions on validation pairs (each with its first
pose and source fitted, as it will generate) and the model is the epoch with the highest
R-precision (``evaluation.t2m.selection``), not the last: the state then also keeps that
epoch's ``best.pt`` (weights only, about 6 MB compact), since a later part may not beat it.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT))   # experiments.lab

STATE = Path("experiments/state/twostream_recipe")   # relative to ROOT: committed
WORK = Path("runs/twostream_parts")                   # relative to ROOT: not kept
RECIPE = {"h": 128, "batch_size": 32, "length_buckets": 20, "z_every_step": True,
          "progress_input": True, "lambdas": {"energy": 10.0}, "checkpoint_every": 50,
          "mirror": True, "normalise": "by-source"}
# (epoch the phase ends at, learning rate, decayed epochs at its end): one part each
PHASES: tuple[tuple[int, float, float], ...] = ((6, 1e-3, 2), (12, 5e-4, 3),
                                                 (18, 2.5e-4, 3))


def plan(part: int) -> tuple[int, int, float, float]:
    """Part ``part`` -> (epoch it starts from, epoch it ends at, its learning rate, the
    epochs at its end whose rate decays)."""
    if not 1 <= part <= len(PHASES):
        raise ValueError(f"PART must be 1..{len(PHASES)}, got {part}")
    start = PHASES[part - 2][0] if part > 1 else 0
    end, lr, decay = PHASES[part - 1]
    return start, end, lr, decay


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("part", type=int)
    ap.add_argument("--data", nargs="*", default=[],
                    help="sources beside the procedural corpus, e.g. bandai:DIR@1")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--full-state", action="store_true",
                    help="save the exact state (about 37 MB) instead of the compact one")
    ap.add_argument("--select-evaluator", default=None,
                    help="keep the epoch of the highest validation R-precision under this "
                         "evaluator (its best.pt travels with the state)")
    ap.add_argument("--select-data", default=None,
                    help="the source whose validation pairs it scores, e.g. "
                         "bandai:../shared/data/bandai")
    ap.add_argument("--save-only", action="store_true",
                    help="train nothing: save the run folder's last checkpoint as the state "
                         "(a part the session's end interrupts; the same part resumes it)")
    a = ap.parse_args(argv)
    try:
        start, end, lr, decay = plan(a.part)
        if a.select_data and not a.select_evaluator:
            raise ValueError("--select-data needs --select-evaluator")
        if RECIPE.get("normalise") == "by-source" and not a.data:
            raise ValueError("the recipe normalises each source by its own motions: give "
                             "--data (e.g. bandai:../shared/data/bandai@1) beside the corpus")
    except ValueError as exc:
        print(f"twostream_parts.py: {exc}", file=sys.stderr)
        return 2
    os.chdir(ROOT)          # the run records its --data as given: the same text every part
    import torch
    from experiments.lab.run_state import read_state, restore_state, save_state

    import motionlang as ml
    from motionlang.errors import MotionlangError
    from motionlang.training.run_files import read_training_checkpoint
    torch.set_num_threads(a.threads)
    keep_best = bool(a.select_evaluator)   # the best epoch may be an earlier part's
    corpus = WORK / "corpus"
    if not (corpus / ".done").is_file():
        subprocess.run([str(Path(sys.executable).with_name("motionlang")), "data", "synth",
                        "--out", str(corpus), "--n", "6000", "--seed", "0"], check=True)
        (corpus / ".done").touch()
    run = WORK / "run"
    data = [f"{corpus}@1" if a.data else str(corpus), *a.data]
    try:
        if a.save_only:
            about = save_state(run, STATE, part=a.part, data=data, compact=not a.full_state,
                               keep_best=keep_best)
            print(f"part {a.part} saved where it stopped: epoch {about['epoch']}, batch "
                  f"{about['batch']}; run part {a.part} again to finish it")
        elif (run / "last.pt").is_file():
            epoch = read_training_checkpoint(run / "last.pt")["epoch"]
            if not start <= epoch <= end:
                raise MotionlangError(f"{run}: at epoch {epoch}, outside part {a.part} "
                                      f"(epochs {start}..{end}): remove it or run that part")
            print(f"{run}: continuing this session's run folder (epoch {epoch})")
        elif (STATE / "state.json").is_file():
            # a part resumes the state its predecessor saved at its start, or its own,
            # saved where a session's end stopped it (--save-only)
            saved = read_state(STATE)
            at = f"saved at epoch {saved['epoch']} batch {saved['batch']}"
            if not start <= saved["epoch"] < end:
                raise MotionlangError(
                    f"{STATE}: {at}, outside part {a.part} (epochs {start}..{end}): " + (
                        "part 1 would start over" if not start else
                        f"run the part that ends at epoch {start} first"
                        if saved["epoch"] < start else "this part is done: run the next"))
            restore_state(STATE, run)
        elif start:
            read_state(STATE)   # no saved state: one line saying so
        if not a.save_only:
            recipe = dict(RECIPE)
            if a.select_evaluator:
                recipe.update(select_evaluator=a.select_evaluator, select_data=a.select_data)
            model = ml.train("twostream", data, run, resume=(run / "last.pt").is_file(),
                             epochs=end, lr=lr, decay_epochs=decay, **recipe)
            about = save_state(run, STATE, part=a.part, data=data,
                               compact=not a.full_state, keep_best=keep_best)
            if a.part == len(PHASES):
                (STATE / "model.pt").write_bytes(model.read_bytes())
    except MotionlangError as exc:
        print(f"twostream_parts.py: {exc}", file=sys.stderr)
        return 2
    size = sum(p.stat().st_size for p in STATE.rglob("*") if p.is_file())
    print(f"part {a.part} {'saved' if a.save_only else 'done'}: epoch {about['epoch']}, "
          f"step {about['step']}; "
          f"{STATE} holds {size / 1e6:.1f} MB. Commit it:\n"
          f"  git add {STATE} && git commit -m 'twostream recipe: part {a.part} "
          f"(epoch {about['epoch']})' -- {STATE}")
    if a.part == len(PHASES) and not a.save_only:
        print(f"the model (the selected epoch, with --select-evaluator) is {STATE / 'model.pt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The two-stream recipe (``experiments/twostream_recipe.sh``: 20 epochs at the full rate,
then 4 with the learning rate decayed) trained in parts of a few epochs each, one part per
session, on a fresh checkout: run folders are not kept between sessions, so each part
starts from a state committed to the repository and ends by replacing it.

    OMP_NUM_THREADS=1 .venv/bin/python experiments/twostream_parts.py PART
        [--epochs-per-part 4] [--data SOURCE ...] [--mirror] [--threads 1] [--full-state]
        [--select-evaluator EVALUATOR --select-data SOURCE]

The packaged model's data (``scripts/train_shipped_models.sh``): ``--data
bandai:../shared/data/bandai@1 --mirror`` (the corpus then gets ``@1`` too: half of each
epoch each).

Part 1 starts the run; part N continues from the state the part before committed, in
``experiments/state/twostream_recipe/`` (``training.run_state``: the trainer's ``last.pt``
with the optimiser's moments and the RNG states, ``run.json``, ``splits/``,
``history.json``, ``commands.jsonl``, ``state.json``; about 37 MB at h = 128, and so by
default stored compact: ``save_state(compact=True)``, ``last.pt.xz`` with the weights in
float16 and the moments in bfloat16, about 14 MB, small enough to commit beside the
package; ``--full-state`` keeps it exact). Parts
1..5 (4 epochs each: an epoch took 15-19 minutes on one shared core, the data preparation
about 10 more) reach epoch 20, part 6 runs the 4 decayed epochs; the last part also puts
``model.pt`` there. With ``--full-state`` the parts give the model of one uninterrupted
run bit for bit (``tests/test_run_state.py``). A part rebuilds the corpus (``data synth``,
seed 0) and the features from it first (minutes; the features through the on-disk cache) and checks them
against the saved split and normaliser. Printed at the end: what to commit. A compact state
resumes the run up to the rounding of its weights and moments (``training.run_state``).
Run a part again after an interruption in the same session: it continues from the run
folder's own ``last.pt`` (checkpoints every 50 steps). A part that a session's end would cut
short: stop it, ``PART --save-only`` saves where it stopped (the last checkpoint) as the
state to commit, and the next session runs the same PART again to finish it.

``--select-evaluator`` scores every epoch's motions on validation pairs and the model is the
epoch with the highest R-precision (``evaluation.t2m.selection``), not the last: the
state then also keeps that epoch's ``best.pt`` (weights only, about 6 MB compact), since a
later part may not beat it. Give it (with ``--select-data``) to every part.
"""
from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

STATE = Path("experiments/state/twostream_recipe")   # relative to ROOT: committed
WORK = Path("runs/twostream_parts")                   # relative to ROOT: not kept
RECIPE = {"h": 128, "batch_size": 32, "length_buckets": 20, "z_every_step": True,
          "progress_input": True, "lambdas": {"energy": 10.0}, "checkpoint_every": 50}
FULL_EPOCHS, DECAY_EPOCHS = 20, 4


def plan(part: int, per_part: int) -> tuple[int, int, int]:
    """Part ``part`` -> (epoch it starts from, epoch it ends at, decayed epochs of the run
    it resumes: 0 until the decay part)."""
    if per_part < 1:
        raise ValueError(f"--epochs-per-part must be at least 1, got {per_part}")
    full_parts = math.ceil(FULL_EPOCHS / per_part)
    if part < 1 or part > full_parts + 1:
        raise ValueError(f"PART must be 1..{full_parts + 1} with --epochs-per-part {per_part}, "
                         f"got {part}")
    if part <= full_parts:
        return (part - 1) * per_part, min(part * per_part, FULL_EPOCHS), 0
    return FULL_EPOCHS, FULL_EPOCHS + DECAY_EPOCHS, DECAY_EPOCHS


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("part", type=int)
    ap.add_argument("--epochs-per-part", type=int, default=4)
    ap.add_argument("--data", nargs="*", default=[],
                    help="sources beside the procedural corpus, e.g. bandai:DIR@1")
    ap.add_argument("--mirror", action="store_true",
                    help="also train on the motions mirrored left/right (as the package)")
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
        start, end, decay = plan(a.part, a.epochs_per_part)
        if a.select_data and not a.select_evaluator:
            raise ValueError("--select-data needs --select-evaluator")
    except ValueError as exc:
        print(f"twostream_parts.py: {exc}", file=sys.stderr)
        return 2
    os.chdir(ROOT)          # the run records its --data as given: the same text every part
    import torch

    import motionlang as ml
    from motionlang.errors import MotionlangError
    from motionlang.training.run_files import read_training_checkpoint
    from motionlang.training.run_state import read_state, restore_state, save_state
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
            recipe = {**RECIPE, "mirror": True} if a.mirror else dict(RECIPE)
            if a.select_evaluator:
                recipe.update(select_evaluator=a.select_evaluator, select_data=a.select_data)
            model = ml.train("twostream", data, run, resume=(run / "last.pt").is_file(),
                             epochs=end, decay_epochs=decay, **recipe)
            about = save_state(run, STATE, part=a.part, data=data,
                               compact=not a.full_state, keep_best=keep_best)
            if decay:
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
    if end == FULL_EPOCHS and not a.save_only:
        print(f"the model of the first 20 epochs (the selected one, with "
              f"--select-evaluator) is {run / 'model.pt'} (this session only): "
              f"motionlang evaluate-t2m --data {corpus} --model ts20={run / 'model.pt'} "
              f"--autoencode --true-start --oracle 3 -o {WORK / 't2m_20'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

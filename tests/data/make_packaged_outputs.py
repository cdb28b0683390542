"""Write ``packaged_outputs.npz``: every packaged model's outputs, for
``tests/test_packaged_outputs.py``.

Runs that test module's own recipe (``outputs``), so what is pinned is what the test
recomputes. Make it from a clean checkout of the commit to pin, with one torch thread (set
here), and name that checkout's sources first::

    git worktree add /tmp/base COMMIT
    PYTHONPATH=/tmp/base/src .venv/bin/python tests/data/make_packaged_outputs.py
    git worktree remove /tmp/base --force

``--add-inputs`` instead stores the M2L input motion by value in an existing file whose inputs
are pinned by a sha256 only (older fixtures): the motion is recomputed, checked against that
sha256, written beside the outputs, and every other array is kept byte for byte (checked
after writing).

``--add-model NAME`` adds one newly packaged model's outputs to the existing file, every
other array kept byte for byte (checked after writing): a new model is pinned without
recomputing the others on another machine. ``--renew-model NAME`` recomputes one model's
outputs in place, for a change of code meant to move them (its commit says why), every
other model's arrays kept byte for byte.
"""
from __future__ import annotations

import argparse
import hashlib
import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TEST = HERE.parent / "test_packaged_outputs.py"


def source_commit(src: Path) -> str:
    """The short commit of the checkout holding ``src``, marked ``-dirty`` if its sources
    differ from it."""
    git = ["git", "-C", str(src)]
    head = subprocess.run([*git, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True, check=True).stdout.strip()
    dirty = subprocess.run([*git, "status", "--porcelain", "--", "."], capture_output=True,
                           text=True, check=True).stdout.strip()
    return head + ("-dirty" if dirty else "")


def motion_digest(motion) -> str:
    """sha256 of a Motion's frame rate and float64 arrays, as older fixtures pinned their
    input with (``input/synth_sha256``)."""
    h = hashlib.sha256(np.float64(motion.fps).tobytes())
    for a in (motion.root_translation, motion.root_rotation, motion.joint_angles):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.hexdigest()


def rewrite(recipe, path: Path, old: dict, arrays: dict) -> None:
    """Write ``arrays`` to the fixture ``path``, every array of ``old`` checked to come back
    byte for byte, and none the recipe expects missing."""
    missing = set(recipe.expected_keys()) - set(arrays)
    if missing:
        raise SystemExit(f"{path} lacks {sorted(missing)}")
    np.savez_compressed(path, **arrays)
    with np.load(path, allow_pickle=False) as z:
        changed = [k for k, a in old.items() if not (
            z[k].dtype == a.dtype and z[k].shape == a.shape and np.array_equal(z[k], a))]
    if changed:
        raise SystemExit(f"{path}: arrays changed on rewriting: {changed}")


def add_inputs(recipe, path: Path) -> None:
    """Store the input motion by value in the fixture ``path``, its outputs left as they are."""
    with np.load(path, allow_pickle=False) as z:
        old = {k: z[k] for k in z.files}
    motion = recipe.synth_motion()
    digest = old.pop("input/synth_sha256", None)
    if digest is None:
        raise SystemExit(f"{path}: no input/synth_sha256 to check the input against")
    if motion_digest(motion) != str(digest):
        raise SystemExit(f"{path}: datasets.synth no longer gives the pinned input motion "
                         "(its sha256 differs); regenerate the whole file instead")
    arrays = {**old, **recipe.synth_inputs(motion)}
    rewrite(recipe, path, old, arrays)
    print(f"{path}: input motion stored by value, {len(old)} arrays kept", file=sys.stderr)


def model_outputs(recipe, path: Path, name: str) -> tuple[dict, dict]:
    """``(the fixture's arrays, the packaged model name's outputs on its stored inputs)``."""
    with np.load(path, allow_pickle=False) as z:
        old = {k: z[k] for k in z.files}
    if name not in recipe.MODELS:
        raise SystemExit(f"{name}: not in the recipe's MODELS")
    motion = recipe.stored_motion(old)
    return old, recipe.outputs(name, recipe.MODELS[name], motion, old["input/judge_p21"])


def add_model(recipe, path: Path, name: str) -> None:
    """Add the outputs of the packaged model ``name`` to the fixture ``path``."""
    old, new = model_outputs(recipe, path, name)
    rewrite(recipe, path, old, {**old, **new})
    print(f"{path}: {len(new)} arrays of {name} added, {len(old)} kept", file=sys.stderr)


def renew_model(recipe, path: Path, name: str) -> None:
    """Recompute the outputs of the packaged model ``name`` in the fixture ``path``."""
    old, new = model_outputs(recipe, path, name)
    if not set(new) <= set(old):
        raise SystemExit(f"{path}: {name} is not pinned yet (--add-model)")
    kept = {k: a for k, a in old.items() if k not in new}
    rewrite(recipe, path, kept, {**old, **new})
    moved = [k for k in new if not (new[k].shape == old[k].shape and
                                    np.array_equal(new[k], old[k]))]
    print(f"{path}: {name} recomputed, {len(moved)} of its {len(new)} arrays moved "
          f"({', '.join(moved) or 'none'}), {len(kept)} others kept", file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out", type=Path, default=HERE / "packaged_outputs.npz")
    parser.add_argument("--add-inputs", action="store_true",
                        help="store the input motion by value in the existing file -o, "
                             "keeping its outputs")
    parser.add_argument("--add-model", metavar="NAME",
                        help="add one packaged model's outputs to the existing file -o")
    parser.add_argument("--renew-model", metavar="NAME", action="append",
                        help="recompute one packaged model's outputs in the existing file "
                             "-o (again for more)")
    args = parser.parse_args()

    import torch
    torch.set_num_threads(1)
    import motionlang
    src = Path(motionlang.__file__).resolve().parent
    print(f"motionlang from {src}", file=sys.stderr)

    spec = importlib.util.spec_from_file_location("pinned_recipe", TEST)
    recipe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(recipe)
    if args.add_inputs:
        add_inputs(recipe, args.out)
        return
    if args.add_model:
        add_model(recipe, args.out, args.add_model)
        return
    if args.renew_model:
        for name in args.renew_model:
            renew_model(recipe, args.out, name)
        return

    motion = recipe.synth_motion()
    p21 = recipe.judge_input(motion)
    arrays: dict[str, np.ndarray] = {
        **recipe.synth_inputs(motion),
        "input/judge_p21": p21,
        "meta/commit": np.array(source_commit(src)),
        "meta/torch": np.array(torch.__version__),
        "meta/numpy": np.array(np.__version__),
    }
    for name, kind in recipe.MODELS.items():
        arrays.update(recipe.outputs(name, kind, motion, p21))
    missing = set(recipe.expected_keys()) - set(arrays)
    if missing:
        raise SystemExit(f"recipe gave no {sorted(missing)}")
    np.savez_compressed(args.out, **arrays)
    print(f"{args.out}: {len(arrays)} arrays, {args.out.stat().st_size / 1024:.0f} KiB, "
          f"from {arrays['meta/commit']}", file=sys.stderr)


if __name__ == "__main__":
    main()

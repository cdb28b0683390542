"""Write ``packaged_outputs.npz``: every packaged model's outputs, for
``tests/test_packaged_outputs.py``.

Runs that test module's own recipe (``outputs``), so what is pinned is what the test
recomputes. Make it from a clean checkout of the commit to pin, with one torch thread (set
here), and name that checkout's sources first::

    git worktree add /tmp/base COMMIT
    PYTHONPATH=/tmp/base/src .venv/bin/python tests/data/make_packaged_outputs.py
    git worktree remove /tmp/base --force
"""
from __future__ import annotations

import argparse
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out", type=Path, default=HERE / "packaged_outputs.npz")
    args = parser.parse_args()

    import torch
    torch.set_num_threads(1)
    import motionlang
    src = Path(motionlang.__file__).resolve().parent
    print(f"motionlang from {src}", file=sys.stderr)

    spec = importlib.util.spec_from_file_location("pinned_recipe", TEST)
    recipe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(recipe)

    motion = recipe.synth_motion()
    p21 = recipe.judge_input(motion)
    arrays: dict[str, np.ndarray] = {
        "input/synth_sha256": np.array(recipe.motion_digest(motion)),
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

"""How far each pinned output of ``packaged_outputs.npz`` moves under other float kernels.

Recomputes the test's recipe (``tests/test_packaged_outputs.py``) in child processes whose
environment forces other kernels (OpenBLAS's core type, torch's CPU capability, MKL's and
oneDNN's instruction sets, numpy's SIMD dispatch) and prints, per key and setting, the
largest absolute difference from the fixture and that difference over the key's largest
magnitude, as a Markdown table; also the test's tolerance of each key and the largest
difference as a fraction of it. The tolerances of the test are chosen from this table::

    .venv/bin/python tests/data/measure_kernel_drift.py [--models m2l judge ...]
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TEST = HERE.parent / "test_packaged_outputs.py"
#: numpy's dispatch targets past AVX2, and past SSE4.2 (``NPY_DISABLE_CPU_FEATURES``)
NPY_NO_AVX512 = "X86_V4 AVX512_ICL AVX512_SPR"
NPY_NO_AVX = "X86_V3 " + NPY_NO_AVX512

#: label -> environment of the child
SETTINGS: dict[str, dict[str, str]] = {
    "native": {},
    "haswell-avx2": {"OPENBLAS_CORETYPE": "Haswell", "ATEN_CPU_CAPABILITY": "avx2"},
    "sandybridge-default": {"OPENBLAS_CORETYPE": "Sandybridge",
                            "ATEN_CPU_CAPABILITY": "default"},
    # an AVX2 machine as far as every library can be told: MKL (torch's BLAS), oneDNN
    # (torch's convolutions) and numpy's own loops too
    "avx2-all": {"OPENBLAS_CORETYPE": "Haswell", "ATEN_CPU_CAPABILITY": "avx2",
                 "MKL_ENABLE_INSTRUCTIONS": "AVX2", "ONEDNN_MAX_CPU_ISA": "AVX2",
                 "NPY_DISABLE_CPU_FEATURES": NPY_NO_AVX512},
    # the oldest x86-64 kernels every library still has
    "sse-all": {"OPENBLAS_CORETYPE": "Prescott", "ATEN_CPU_CAPABILITY": "default",
                "MKL_ENABLE_INSTRUCTIONS": "SSE4_2", "ONEDNN_MAX_CPU_ISA": "SSE41",
                "NPY_DISABLE_CPU_FEATURES": NPY_NO_AVX},
}


def drift(want: np.ndarray, got: np.ndarray) -> str:
    """One table cell: ``abs / rel`` (rel: over the key's largest magnitude), ``0`` where
    bit-equal, ``same``/``DIFFERS`` for text, the shapes where they differ."""
    if want.dtype.kind == "U":
        return "same" if got.dtype.kind == "U" and got.tolist() == want.tolist() else "DIFFERS"
    if got.shape != want.shape:
        return f"shape {got.shape} vs {want.shape}"
    if np.array_equal(got, want):
        return "0"
    d = float(np.max(np.abs(got.astype(np.float64) - want.astype(np.float64))))
    return f"{d:.1e} / {d / max(float(np.max(np.abs(want))), 1e-300):.1e}"


def limit(recipe, key: str, want: np.ndarray) -> float | None:
    """The test's tolerance of ``key`` (``atol + rtol * max|pinned|``, in the key's units),
    None for text, compared exactly."""
    tol = recipe.tolerance(key)
    if tol == "exact":
        return None
    atol, rtol = tol
    return atol + rtol * float(np.max(np.abs(want)))


def worst(want: np.ndarray, got: list[np.ndarray], lim: float | None) -> str:
    """The largest difference over the settings as a fraction of the tolerance."""
    if lim is None:
        return "exact"
    if any(g.shape != want.shape for g in got):
        return "shape"
    d = max(float(np.max(np.abs(g.astype(np.float64) - want.astype(np.float64)))) for g in got)
    return f"{d / lim:.1e}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", help="these packaged models only")
    parser.add_argument("--settings", nargs="+", choices=list(SETTINGS), default=list(SETTINGS))
    args = parser.parse_args()
    spec = importlib.util.spec_from_file_location("pinned_recipe", TEST)
    recipe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(recipe)
    names = args.models or list(recipe.MODELS)
    with np.load(recipe.FIXTURE, allow_pickle=False) as z:
        pinned = {k: z[k] for k in z.files}
    got: dict[str, dict[str, np.ndarray]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label in args.settings:
            got[label] = recipe.recompute_elsewhere(SETTINGS[label], names,
                                                    Path(tmp) / f"{label}.npz")
            print(f"{label}: {got[label]['kernel/openblas']} / {got[label]['kernel/torch']}",
                  file=sys.stderr)
    keys = [k for k in recipe.expected_keys()
            if k.startswith("input/synth") or k.split("/")[0] in names]
    print("| key | " + " | ".join(args.settings) + " | tolerance | worst / tolerance |")
    print("|---|" + "---|" * (len(args.settings) + 2))
    for k in keys:
        cells = [drift(pinned[k], got[label][k]) for label in args.settings]
        lim = limit(recipe, k, pinned[k])
        ratio = worst(pinned[k], [got[label][k] for label in args.settings], lim)
        print(f"| `{k}` | " + " | ".join(cells) + " | "
              + ("exact" if lim is None else f"{lim:.1e}") + f" | {ratio} |")


if __name__ == "__main__":
    main()

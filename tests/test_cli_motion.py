"""``motionlang info | render | convert | demo`` through ``cli.main.main``."""
import json
import re

import imageio.v3 as iio
import numpy as np
import pytest

from helpers.data import shared_file
from motionlang.cli.main import main
from motionlang.datasets import named


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_info_json_kit(capsys):
    path = shared_file("kitml/00001_mmm.xml")
    code, out, _ = run(capsys, "info", path, "--json")
    assert code == 0
    info = json.loads(out)
    assert info["frames"] == 378 and info["fps"] == 100.0 and info["dofs"] == 44
    assert info["duration_s"] == pytest.approx(3.78)
    assert info["source_format"] == "mmm"
    assert len(info["joint_names"]) == info["joints"] == 44  # the "44 joints"
    assert info["nodes"] > 44 and "BPx_joint" in info["joint_names"]


def test_info_amc_with_asf_text(capsys):
    amc = shared_file("cmu35/35_01.amc")
    code, out, _ = run(capsys, "info", amc, "--asf", shared_file("cmu35/35.asf"))
    assert code == 0
    assert "358" in out and "120" in out
    code, out, _ = run(capsys, "info", amc, "--json", "--source-fps", "60")
    assert json.loads(out)["fps"] == 60.0


def test_info_mit_mat_sequences(capsys):
    mat = shared_file("mit/motion.mat")
    code, out, _ = run(capsys, "info", mat, "--json", "--sequence", "2")
    assert code == 0 and json.loads(out)["frames"] == 260 and json.loads(out)["fps"] == 30.0
    code, _, err = run(capsys, "info", mat, "--sequence", "9")
    assert code == 2 and str(mat) in err and "no sequence 9" in err
    code, _, err = run(capsys, "info", shared_file("kitml/00001_mmm.xml"), "--sequence", "2")
    assert code == 2 and "--sequence applies to .mat" in err


def test_render_gif_clip_and_strip(tmp_path, capsys):
    src = shared_file("kitml/00001_mmm.xml")
    gif = tmp_path / "out" / "walk.gif"
    code, out, _ = run(capsys, "render", src, gif, "--start", "1", "--end", "1.5", "--fps", "10")
    assert code == 0 and out.strip() == str(gif)
    assert iio.imread(gif, index=None).shape[0] == 6  # 0.5 s at 10 fps, both ends
    png = tmp_path / "strip.png"
    widths = []
    for n in (2, 5):
        assert run(capsys, "render", src, png, "--strip", n)[0] == 0
        widths.append(iio.imread(png).shape[1])
    assert widths[0] < widths[1]
    traj = tmp_path / "traj.png"
    assert run(capsys, "render", src, traj, "--trajectory")[0] == 0 and traj.is_file()
    # OUT as -o too, as every other command takes it; one of the two, not both or none
    again = tmp_path / "again.png"
    assert run(capsys, "render", src, "-o", again)[0] == 0 and again.is_file()
    for argv in ((src,), (src, again, "-o", tmp_path / "other.png")):
        code, _, err = run(capsys, "render", *argv)
        assert code == 2 and err.count("\n") == 1 and "output" in err
    assert not (tmp_path / "other.png").exists()


def test_convert_to_bvh_round_trip(tmp_path, capsys):
    from motionlang.formats import read_motion

    src = shared_file("kitml/00001_mmm.xml")
    out = tmp_path / "walk.bvh"
    code, _, _ = run(capsys, "convert", src, out, "--end", "1")
    assert code == 0
    back = read_motion(out)
    orig = read_motion(src)[:101]
    assert back.n_frames == 101 and back.fps == pytest.approx(100.0)
    # the BVH may add end sites; compare the joints both skeletons have
    common = [n for n in orig.skeleton.names if n in back.skeleton]
    assert len(common) > 20
    ib = [back.skeleton.index(n) for n in common]
    io = [orig.skeleton.index(n) for n in common]
    assert np.allclose(back.positions()[:, ib], orig.positions()[:, io], atol=2e-3)


def test_bad_inputs_exit_2_naming_the_file(tmp_path, capsys):
    missing = tmp_path / "nope.xml"
    code, _, err = run(capsys, "info", missing)
    assert code == 2 and str(missing) in err and "Traceback" not in err
    bad = tmp_path / "bad.xml"
    bad.write_text("<MMM><Motion><not closed")
    out = tmp_path / "bad.gif"
    code, _, err = run(capsys, "render", bad, out)
    assert code == 2 and str(bad) in err
    assert not out.exists()
    code, _, err = run(capsys, "render", bad, tmp_path / "x.avi")
    assert code == 2 and "x.avi" in err
    code, _, err = run(capsys, "convert", bad, tmp_path / "x.bvh")
    assert code == 2 and str(bad) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.xml"]


def test_render_empty_clip_is_an_error(tmp_path, capsys):
    src = shared_file("kitml/00001_mmm.xml")
    out = tmp_path / "a.gif"
    code, _, err = run(capsys, "render", src, out, "--start", "10")
    assert code == 2 and "no frames" in err and not out.exists()


def _scores(out, label):
    return [float(line.split("=")[1].split()[0]) for line in out.splitlines()
            if line.strip()[:1].isdigit() and label in line]


def test_demo_main_job_offline_with_packaged_models(tmp_path, capsys, monkeypatch):
    # The README's main job on a machine without shared data: the packaged L2M generates,
    # the packaged M2L describes a procedural sample; GIF, strip and BVH are written.
    from motionlang.formats import read_motion
    monkeypatch.setattr(named, "data_dirs", lambda: [tmp_path])
    out_dir = tmp_path / "o"
    code, out, _ = run(capsys, "demo", "--out", out_dir, "-w", "3", "--max-frames", "12")
    assert code == 0
    assert "no shared data" in out
    gen, desc = _scores(out, "log L"), _scores(out, "log P")
    # the packaged L2M (joint positions) decodes its expected frames: one motion
    assert len(gen) == 1 and "expected frames" in out
    grounded = [line for line in out.splitlines() if line.strip()[:1].isdigit()
                and "grounded" in line]     # the analysis' sentence, no model score
    assert 1 <= len(desc) + len(grounded) <= 3 and desc   # one procedural motion described
    assert all(s < 0 for s in desc)
    # as 'motionlang describe' gives them: each once, no gender (its captions drew one by
    # chance), none broken
    from motionlang.analysis import garbled
    from motionlang.models.seq2seq.decode.grounded import GENDERED
    shown = [m[2] for m in re.finditer(r"log P =\s*(-?[\d.]+)  (.+)", out)]
    assert len(shown) == len(desc) == len(set(shown)) and all(t.split() for t in shown)
    assert not any(garbled(t) or set(t.split()) & set(GENDERED) for t in shown)
    assert gen == sorted(gen, reverse=True)
    written = out.split("written:")[1].split()
    assert [p.rsplit("/", 1)[1] for p in written] == ["generated.gif", "generated_strip.png",
                                                      "generated.bvh"]
    # the packaged M2L learnt from Bandai Namco data: the demo says it is non-commercial
    assert "note: the packaged m2l is CC BY-NC 4.0" in out
    assert iio.imread(written[0], index=0).size > 0
    motion = read_motion(written[2])
    assert 5 <= motion.n_frames * 10 / motion.fps <= 12 + 1e-6  # min 5, cap 12 model frames
    assert np.isfinite(motion.positions()).all()


def test_demo_with_input_describes_and_renders_it(tmp_path, capsys):
    src = shared_file("kitml/00001_mmm.xml")
    code, out, _ = run(capsys, "demo", "--input", src, "--out", tmp_path, "-w", "2",
                       "--max-frames", "6")
    assert code == 0
    grounded = [line for line in out.splitlines() if line.strip()[:1].isdigit()
                and "grounded" in line]
    assert len(_scores(out, "log P")) + len(grounded) == 4   # procedural sample + 00001
    assert f"describe {src}" in out
    names = [p.rsplit("/", 1)[1] for p in out.split("written:")[1].split()]
    assert names[3:] == ["00001_mmm.gif", "00001_mmm_strip.png", "00001_mmm_trajectory.png"]


def test_demo_describes_and_renders_a_cmu_input(tmp_path, capsys):
    src = shared_file("cmu35/35_01.amc")
    code, out, _ = run(capsys, "demo", "--input", src, "--out", tmp_path, "-w", "1",
                       "--max-frames", "6")
    # the packaged M2L reads the 21-joint body, which CMU's skeleton maps onto
    assert code == 0 and "not described" not in out
    assert re.match(r"1\. +(log P =|grounded)",
                    out.split(f"describe {src}")[1].splitlines()[1].lstrip())
    names = [p.rsplit("/", 1)[1] for p in out.split("written:")[1].split()]
    assert "35_01_strip.png" in names and "generated.bvh" in names


def test_demo_says_when_a_rig_cannot_be_described(tmp_path, capsys):
    bvh = tmp_path / "odd.bvh"
    bvh.write_text("HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition "
                   "Zposition\n JOINT b\n {\n  OFFSET 0 10 0\n  CHANNELS 3 Zrotation "
                   "Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 10 0\n  }\n }\n}\n"
                   "MOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0 0 0 0\n0 0 1 0 0 0\n")
    code, out, _ = run(capsys, "demo", "--input", bvh, "--out", tmp_path / "o", "-w", "1",
                       "--max-frames", "6", "--no-render")
    assert code == 0 and "not described" in out and "rig joints not matched: a, b" in out


def test_demo_finds_shared_data(monkeypatch, tmp_path):
    path = shared_file("kitml/00001_mmm.xml")
    monkeypatch.setenv(named.DATA_ENV, str(path.parents[1]))
    monkeypatch.chdir(tmp_path)
    assert named.find_data_file("kitml/00001_mmm.xml") == path

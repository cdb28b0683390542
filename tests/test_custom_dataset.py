"""A folder of BVH / ASF-AMC files plus a captions file (CSV or JSON lines)."""
from __future__ import annotations

import json
import shutil

import pytest

from helpers.data import shared_file
from motionlang.datasets.custom import load_custom, read_captions
from motionlang.errors import DatasetError

BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.033333
0 90 0 0 0 0 0 0 0
0 90 1 0 5 0 0 10 0
0 90 2 0 10 0 0 20 0
"""


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "walk.bvh").write_text(BVH)
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "idle.bvh").write_text(BVH)
    (tmp_path / "notes.txt").write_text("not a motion")
    return tmp_path


def test_csv_captions(folder):
    (folder / "captions.csv").write_text(
        'file,text\nwalk.bvh,A person walks.\n\nwalk.bvh,"Someone, slowly, walks"\n')
    recs = load_custom(folder)
    assert [r.id for r in recs] == ["sub/idle", "walk"]
    idle, walk = recs
    assert walk.annotations == ["A person walks.", "Someone, slowly, walks"]
    assert walk.meta["captions_lines"] == [2, 4]
    assert idle.annotations == [] and not idle.has_annotations


def test_jsonl_captions_and_motion_loading(folder):
    lines = [{"file": "sub/idle.bvh", "text": "A person stands."},
             {"file": "walk.bvh", "text": "A person walks."}]
    (folder / "captions.jsonl").write_text("\n".join(json.dumps(x) for x in lines) + "\n")
    recs = load_custom(folder)
    assert [r.annotations for r in recs] == [["A person stands."], ["A person walks."]]
    pytest.importorskip("motionlang.formats.bvh")
    m = recs[1].load_motion()
    assert m.n_frames == 3 and m.fps == pytest.approx(30.0, rel=1e-3)


def test_asf_amc_folder(tmp_path):
    shutil.copy(shared_file("cmu35/35.asf"), tmp_path / "35.asf")
    shutil.copy(shared_file("cmu35/35_01.amc"), tmp_path / "35_01.amc")
    (tmp_path / "caps.csv").write_text("file,text\n35_01.amc,a man walks forward\n")
    (rec,) = load_custom(tmp_path, tmp_path / "caps.csv")
    assert rec.id == "35_01" and rec.annotations == ["a man walks forward"]
    m = rec.load_motion()
    assert m.n_frames == 358 and m.fps == 120.0


@pytest.mark.parametrize("content, match", [
    ("name,caption\nwalk.bvh,x\n", r"captions.csv:1: expected the header"),
    ("file,text\nwalk.bvh,ok\nwalk.bvh\n", r"captions.csv:3: expected 2 columns"),
    ("file,text\nwalk.bvh,ok\nrun.bvh,a run\n", r"captions.csv:3: unknown motion file 'run.bvh'"),
    ("file,text\nnotes.txt,x\n", r"captions.csv:2: unknown motion file 'notes.txt' \(not a motion"),
    ("file,text\nwalk.bvh,  \n", r"captions.csv:2: empty 'text'"),
])
def test_csv_errors_name_file_and_line(folder, content, match):
    (folder / "captions.csv").write_text(content)
    with pytest.raises(DatasetError, match=match):
        load_custom(folder)


def test_jsonl_errors_and_missing_files(folder, tmp_path):
    p = folder / "captions.jsonl"
    p.write_text('{"file": "walk.bvh", "text": "ok"}\n{"file": "walk.bvh"\n')
    with pytest.raises(DatasetError, match=r"captions.jsonl:2: invalid JSON"):
        load_custom(folder)
    p.write_text('{"file": "walk.bvh", "text": 3}\n')
    with pytest.raises(DatasetError, match=r"captions.jsonl:1: expected"):
        read_captions(p)
    p.unlink()
    with pytest.raises(DatasetError, match="captions.csv, captions.jsonl"):
        load_custom(folder)
    with pytest.raises(DatasetError, match="captions file not found"):
        load_custom(folder, folder / "nope.csv")
    with pytest.raises(DatasetError, match="not found"):
        load_custom(tmp_path / "nowhere")


def test_cli_info_on_custom_folder(folder, capsys):
    from motionlang.cli.main import main
    (folder / "captions.csv").write_text("file,text\nwalk.bvh,a\nwalk.bvh,b\n")
    assert main(["data", "info", str(folder), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["kind"], info["motions"], info["annotations"],
            info["without_annotations"]) == ("custom", 2, 2, 1)


@pytest.mark.parametrize("name", ["../outside/x.bvh", "/etc/x.bvh", "sub/../../outside/x.bvh",
                                  "..\\outside\\x.bvh", "C:/data/x.bvh"])
def test_captions_cannot_leave_the_folder(tmp_path, name):
    folder = tmp_path / "data"
    folder.mkdir()
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "x.bvh").write_text(BVH)
    (folder / "walk.bvh").write_text(BVH)
    (folder / "link.bvh").symlink_to(tmp_path / "outside" / "x.bvh")  # a link inside
    (folder / "captions.csv").write_text(f"file,text\nwalk.bvh,ok\n{name},escaped\n")
    with pytest.raises(DatasetError, match=r"captions.csv:3: motion file .* is outside the "
                                           "dataset folder"):
        load_custom(folder)


def test_links_inside_the_folder(tmp_path):
    folder = tmp_path / "data"
    folder.mkdir()
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "x.bvh").write_text(BVH)
    (folder / "link.bvh").symlink_to(tmp_path / "outside" / "x.bvh")
    (folder / "dirlink").symlink_to(tmp_path / "outside")
    (folder / "inner.bvh").write_text(BVH)
    (folder / "alias.bvh").symlink_to(folder / "inner.bvh")
    (folder / "captions.csv").write_text("file,text\nalias.bvh,a file linked in\n"
                                         "./sub/../alias.bvh,the same, spelt oddly\n")
    # a link to a file of the folder is one of its files
    rec = next(r for r in load_custom(folder) if r.id == "alias")
    assert len(rec.annotations) == 2
    # a file link out of the folder is refused like a folder link (issue 44, item 0)
    (folder / "captions.csv").write_text("file,text\nlink.bvh,a file linked in\n")
    with pytest.raises(DatasetError, match="link.bvh.*a symbolic link in .* leads outside it"):
        load_custom(folder)
    (folder / "captions.csv").write_text("file,text\ndirlink/x.bvh,through a folder link\n")
    with pytest.raises(DatasetError, match="a symbolic link in .* leads outside it"):
        load_custom(folder)

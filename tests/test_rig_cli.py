"""``motionlang rig show | template`` through ``cli.main.main``, on hand-written rig fixtures."""
import json

from helpers import rigs as rf
from helpers.auto_rigs import mirrored
from helpers.data import shared_file
from motionlang.cli.main import main
from motionlang.features.joint_map import KIT21_NAMES

ODD = rf.Rig("odd", 0.01, """
pelvis_bone 0 0 0
  hip_{s} 9 -3 0
    knee_{s} 0 -44 0
      ankle_{s} 0 -43 0
        ball_{s} 0 -7 13
          * 0 0 5
  back 0 10 0
    ribs 0 12 0
      neck_base 0 26 0
        skull 0 8 0
          * 0 20 0
      clav_{s} 3 22 0
        arm_{s} 15 0 0
          elbow_{s} 30 0 0
            wrist_{s} 25 0 0
              * 8 0 0
""", ("hip_L", "hip_R"), ("knee_L", "knee_R"), ("arm_L", "arm_R"), arms_down=75)


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_show_prints_joints_map_and_sources(tmp_path, capsys):
    path = rf.write(rf.RIGS["bandai"], tmp_path)
    code, out, _ = run(capsys, "rig", "show", path)
    assert code == 0
    assert "joints (+ 5 end sites)" in out and "Hips, Spine, Chest, Neck, Head" in out
    assert "map      bandai: Bandai Namco" in out
    rows = {line.split()[0]: line.split("<- ")[1] for line in out.splitlines() if "<- " in line
            and not line.strip().startswith("body")}
    assert list(rows) == list(KIT21_NAMES)
    assert rows["root"] == "mid(UpperLeg_L, UpperLeg_R)" and rows["LS"] == "UpperArm_L"
    assert rows["RMrot"] == "lerp(Foot_R, Toes_R, 0.4)"
    unused = out.split("unused   ")[1]  # the reader may drop joint_Root, a floor node
    assert unused.split(", ")[-3:] == ["Hips", "Shoulder_L", "Shoulder_R\n"]
    code, out, _ = run(capsys, "rig", "show", path, "--json")
    shown = json.loads(out)
    assert shown["map"] == "bandai" and shown["body"]["root"] == ["mid", "UpperLeg_L",
                                                                   "UpperLeg_R"]


def test_no_fit_then_template_then_joint_map(tmp_path, capsys):
    path = rf.write(ODD, tmp_path)
    code, out, _ = run(capsys, "rig", "show", path)   # no table fits: mapped automatically
    assert code == 0 and "map      auto: automatic" in out
    assert "    LS     name     1.00 <- arm_L" in out and "    BT     topology 0.90 <- ribs" in out
    # mirrored, its names contradict its rest pose: an error that offers a map of one's own
    code, out, err = run(capsys, "rig", "show", rf.write(mirrored(ODD), tmp_path, "flipped"))
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "rig joints not matched: pelvis_bone, hip_L" in err and "skull" in err
    assert err.strip().endswith("motionlang rig template FILE > map.json")
    code, out, _ = run(capsys, "rig", "template", path)
    assert code == 0
    template = json.loads(out)
    assert template["rig_joints"][:3] == ["pelvis_bone", "hip_L", "knee_L"]
    from motionlang.features.joint_map import KIT21_NAMES
    lines = out.splitlines()   # one line per body joint, easy to edit by hand
    assert all(sum(ln.lstrip().startswith(f'"{n}": ') for ln in lines) == 1 for n in KIT21_NAMES)
    fill = {"root": ["mid", "hip_L", "hip_R"], "BP": "back", "BT": "ribs",
            "BLN": "neck_base", "BUN": "skull"}
    for s in "LR":
        fill.update({f"{s}S": f"arm_{s}", f"{s}E": f"elbow_{s}", f"{s}W": f"wrist_{s}",
                     f"{s}H": f"hip_{s}", f"{s}K": f"knee_{s}", f"{s}A": f"ankle_{s}",
                     f"{s}Mrot": ["lerp", f"ankle_{s}", f"ball_{s}", 0.4], f"{s}F": f"ball_{s}"})
    template["joints"].update(fill)
    (tmp_path / "map.json").write_text(json.dumps(template))
    code, out, _ = run(capsys, "rig", "show", path, "--joint-map", tmp_path / "map.json")
    assert code == 0 and "map      bvh:odd-map: user map" in out
    assert "    LF     user     1.00 <- ball_L" in out


def test_bad_joint_map_and_missing_file(tmp_path, capsys):
    path = rf.write(ODD, tmp_path)
    (tmp_path / "half.json").write_text(json.dumps({"joints": {"root": "pelvis_bone"}}))
    code, _, err = run(capsys, "rig", "show", path, "--joint-map", tmp_path / "half.json")
    assert code == 2 and "half.json: missing body joints" in err
    # a map of every joint but one, made from the rig's own template: the map is named once
    cc = rf.write(rf.RIGS["cc"], tmp_path)
    code, out, _ = run(capsys, "rig", "template", cc)
    template = json.loads(out)
    del template["joints"]["BP"]
    (tmp_path / "no_bp.json").write_text(json.dumps(template))
    for command in ("info", "describe"):
        code, _, err = run(capsys, command, cc, "--joint-map", tmp_path / "no_bp.json")
        assert code == 2 and "no_bp.json: missing body joints ['BP']" in err
        assert err.count("no_bp.json") == 1, err
    code, _, err = run(capsys, "rig", "template", tmp_path / "absent.bvh")
    assert code == 2 and "absent.bvh" in err and "file not found" in err
    assert run(capsys, "rig")[0] == 2  # no action: help, and the usage error code


def test_show_cmu_amc_with_asf(capsys):
    code, out, _ = run(capsys, "rig", "show", shared_file("cmu35/35_01.amc"), "--asf",
                       shared_file("cmu35/35.asf"))
    assert code == 0 and "map      cmu-asf" in out and "    LK     table    1.00 <- ltibia" in out

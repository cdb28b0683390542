"""motionlang serve over HTTP (no browser): generate, download, describe uploads, rigs,
search, and every bad input as one line with no trace; the command line's options."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from helpers.rigs import RIGS, write
from helpers.web import SMALL, call, post_files, post_json, served
from motionlang.cli.main import main
from motionlang.formats import read_motion
from motionlang.web.options import ServeOptions
from motionlang.web.views import VIEW_FPS, side, view_step


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """The app on a free port, run from an empty folder that must stay empty."""
    with served(tmp_path_factory.mktemp("cwd"), max_upload_mb=2) as url:
        yield url


def test_info_names_the_models_and_formats(server):
    status, info = call(server + "api/info")
    assert status == 200
    assert [m["name"] for m in info["models"]] == ["l2m-procedural"]
    assert info["models"][0]["methods"] == ["sample", "beam", "mean"]
    assert {"bvh", "glb", "mp4"} <= set(info["exports"])
    assert info["search"] is False and info["max_upload_bytes"] == 2 << 20


def test_a_model_that_samples_by_itself_is_offered_its_own_decoding_only():
    import motionlang as ml
    from helpers.twostream import HashTokens
    from motionlang.models.masked.config import MaskedConfig
    from motionlang.models.masked.model import MaskedModel
    from motionlang.web.studio import model_methods
    masked = ml.text_to_motion(MaskedModel(MaskedConfig(width=8, depth=1, code_dim=4, codes=8,
                                                        quantizers=2, hidden=16, heads=2,
                                                        layers=1, res_layers=1), None,
                                           HashTokens()))
    assert model_methods(masked) == ["sample"]


def test_the_page_and_its_scripts_are_served_from_the_package(server):
    status, page = call(server)
    assert status == 200 and b'<canvas id="view"' in page
    for name in ("viewer.js", "app.js", "style.css"):
        status, body = call(server + f"static/{name}")
        assert status == 200 and len(body) > 500
        assert b"http://" not in body and b"https://" not in body   # nothing from elsewhere
    assert call(server + "static/../options.py")[0] == 404


def test_generate_keeps_the_length_asked_for_and_downloads_bvh_and_glb(server, tmp_path):
    status, view = post_json(server + "api/generate", {"text": "a person walks forward",
                                                       "seconds": 4, "seed": 1})
    assert status == 200, view
    assert view["n_frames"] == 50 and view["fps"] == 12.5 and view["n_joints"] == 21
    frames = np.array(view["frames"]).reshape(50, 21, 3)
    assert abs(frames[..., 1].min() - view["floor"]) < 1e-9
    assert np.ptp(frames[:, 0, 2]) > 0.3, "a walk forward moves the root along +Z"
    assert view["sides"][view["names"].index("LK")] == "L"
    status, bvh = call(server + f"api/export/{view['id']}.bvh")
    assert status == 200
    (tmp_path / "walk.bvh").write_bytes(bvh)
    motion = read_motion(tmp_path / "walk.bvh")
    assert motion.n_frames == 50 and motion.fps == pytest.approx(12.5)
    status, glb = call(server + f"api/export/{view['id']}.glb")
    assert status == 200 and glb[:4] == b"glTF"
    from motionlang.formats.gltf_read import read_gltf_animation
    (tmp_path / "walk.glb").write_bytes(glb)
    anim = read_gltf_animation(tmp_path / "walk.glb")
    assert anim.positions.shape[0] == 50 and anim.fps == pytest.approx(12.5)


def test_a_rig_takes_the_generated_motion_and_its_download(server, tmp_path):
    rig = write(RIGS["cmu-bvh"], tmp_path, T=4)
    status, got = post_files(server + "api/rig", [(rig.name, rig.read_bytes())])
    assert status == 200, got
    joints = len(read_motion(rig).skeleton.joints)
    assert got["joints"] == joints and got["name"] == "cmu-bvh"
    status, view = post_json(server + "api/generate", {"text": "a person waves",
                                                       "rig": got["id"]})
    assert status == 200 and view["n_joints"] == joints and view["rig"] == got["id"]
    frames = np.array(view["frames"]).reshape(view["n_frames"], joints, 3)
    head = view["names"].index("Head")
    up = frames[:, head, 1] - frames[:, view["parents"][head], 1]
    assert (up > 0).all(), "the rig's head hangs below its neck"
    names = [j.name for j in read_motion(rig).skeleton.joints]
    status, bvh = call(server + f"api/export/{view['id']}.bvh?rig={got['id']}")
    out = tmp_path / "out.bvh"
    out.write_bytes(bvh)
    assert [j.name for j in read_motion(out).skeleton.joints] == names
    from motionlang.formats.gltf_read import read_gltf_animation
    status, glb = call(server + f"api/export/{view['id']}.glb?rig={got['id']}")
    (tmp_path / "out.glb").write_bytes(glb)
    anim = read_gltf_animation(tmp_path / "out.glb")
    assert set(names) <= set(anim.names) and anim.positions.shape[0] == view["n_frames"]


def test_an_mp4_download_is_a_video(server):
    _, view = post_json(server + "api/generate", {"text": "a person bows", "seconds": 1})
    status, mp4 = call(server + f"api/export/{view['id']}.mp4")
    assert status == 200 and mp4[4:8] == b"ftyp"   # an ISO media file


def test_an_uploaded_bvh_is_described(server, tmp_path):
    bvh = write(RIGS["mixamo"], tmp_path, T=40)
    status, view = post_files(server + "api/describe", [(bvh.name, bvh.read_bytes())])
    assert status == 200, view
    assert view["name"] == "mixamo" and view["n_joints"] == 21
    assert 1 <= len(view["sentences"]) <= 5 and all(s["text"] for s in view["sentences"])
    assert view["timeline"] == []   # a short take


def test_a_long_take_gets_a_timeline(server, tmp_path):
    bvh = write(RIGS["mixamo"], tmp_path, "long_walk", T=390)   # 13 s at 30 Hz
    status, view = post_files(server + "api/describe", [(bvh.name, bvh.read_bytes())])
    assert status == 200 and view["seconds"] == 13.0
    spans = [(s["start"], s["end"]) for s in view["timeline"]]
    assert spans and spans[0][0] == 0.0 and spans[-1][1] == pytest.approx(13.0, abs=0.1)
    assert all(a[1] <= b[0] + 1e-9 for a, b in zip(spans, spans[1:]))


def test_a_small_file_that_claims_hours_is_refused_before_the_models_are_held(server,
                                                                            tmp_path):
    bvh = write(RIGS["mixamo"], tmp_path, T=40)
    text = bvh.read_text()
    old = next(line for line in text.splitlines() if line.startswith("Frame Time:"))
    slow = text.replace(old, "Frame Time: 100").encode()   # 40 frames: 4,000 s
    status, got = post_files(server + "api/describe", [(bvh.name, slow)])
    assert status == 400
    assert got["error"] == ("mixamo: the take lasts 66.7 minutes (40 frames at 0.01 Hz); "
                            "this server describes up to 30 (motionlang serve "
                            "--max-describe-minutes; or motionlang describe FILE)")
    fine = text.replace(old, "Frame Time: 40").encode()     # 1,600 s: within 30 minutes
    assert post_files(server + "api/describe", [(bvh.name, fine)])[0] == 200


@pytest.mark.parametrize("rel", [("cmu35/35_01.amc", "cmu35/35.asf"), ("kitml/00001_mmm.xml",)])
def test_real_amc_asf_and_mmm_uploads_are_described(server, shared_data, rel):
    files = [((shared_data / r).name, (shared_data / r).read_bytes()) for r in rel]
    status, view = post_files(server + "api/describe", files)
    assert status == 200, view
    assert view["n_joints"] == 21 and view["fps"] <= VIEW_FPS   # thinned for the page
    assert view["sentences"] and view["name"] == Path(rel[0]).stem


@pytest.mark.parametrize("files, needle", [
    ([("walk.txt", b"HIERARCHY")], "walk.txt: not a motion file"),
    ([("walk.bvh", b"")], "walk.bvh: the file is empty"),
    ([("walk.bvh", b"HIERARCHY\nROOT Hips\n{\n")], "walk.bvh"),
    ([("01_01.amc", b":FULLY-SPECIFIED\n1\nroot 0 0 0 0 0 0\n")], "needs its .asf"),
    ([("a.bvh", b"x"), ("b.bvh", b"y")], "upload one motion file"),
])
def test_a_bad_upload_is_one_line_naming_the_file(server, files, needle):
    status, body = post_files(server + "api/describe", files)
    assert status == 400
    assert needle in body["error"] and "\n" not in body["error"]
    assert "Traceback" not in body["error"] and "motionlang-serve-" not in body["error"]


def test_an_upload_over_the_limit_is_refused_before_it_is_read(server):
    status, body = post_files(server + "api/describe", [("big.bvh", b"0" * (2200 << 10))])
    assert status == 413 and "--max-upload-mb" in body["error"]


def test_a_chunked_upload_is_counted_and_stopped_at_the_limit(server):
    import http.client
    from urllib.parse import urlsplit
    where = urlsplit(server)
    conn = http.client.HTTPConnection(where.hostname, where.port, timeout=60)
    boundary = "b0undary"
    head = (f'--{boundary}\r\nContent-Disposition: form-data; name="files"; '
            'filename="big.bvh"\r\n\r\n').encode()

    def body():   # no Content-Length: the server counts what arrives
        yield head
        for _ in range(40):
            yield b"0" * (64 << 10)
        yield f"\r\n--{boundary}--\r\n".encode()

    conn.request("POST", "/api/describe", body=body(), encode_chunked=True,
                 headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
    res = conn.getresponse()
    assert res.status == 413 and b"--max-upload-mb" in res.read()
    conn.close()


def test_an_unknown_route_is_one_line(server):
    status, body = call(server + "api/nothing")
    assert status == 404 and body == {"error": "Not Found"}


def test_the_readers_limits_apply_to_uploads(server, tmp_path, monkeypatch):
    bvh = write(RIGS["mixamo"], tmp_path, T=40)
    monkeypatch.setenv("MOTIONLANG_MAX_FRAMES", "10")
    status, body = post_files(server + "api/describe", [(bvh.name, bvh.read_bytes())])
    assert status == 400 and "MOTIONLANG_MAX_FRAMES" in body["error"]


@pytest.mark.parametrize("payload, needle", [
    ({"text": "   "}, "type a sentence"),
    ({"text": "a person walks", "model": "nope"}, "model 'nope' is not offered"),
    ({"text": "a person walks", "seconds": 0}, "length must be in"),
    ({"text": "a person walks", "seconds": 1e6}, "length must be in"),
    ({"text": "a person walks", "method": "greedy"}, "decoding must be one of"),
    ({"text": "a person walks", "rig": "zz"}, "no rig 'zz'"),
    ({"text": "a person walks", "seed": "x"}, "seed"),
    ({"text": "a person walks", "seed": -1}, "seed must be an integer in 0.."),
    ({"text": "a person walks", "seed": 2**70, "method": "sample"}, "seed must be"),
    ({}, "text"),
])
def test_a_bad_request_is_one_line(server, payload, needle):
    status, body = post_json(server + "api/generate", payload)
    assert status == 400 and needle in body["error"] and "\n" not in body["error"]


def test_a_bad_download_is_one_line(server):
    status, body = call(server + "api/export/zz.bvh")
    assert status == 400 and "no take 'zz'" in body["error"]
    _, view = post_json(server + "api/generate", {"text": "a person jumps"})
    status, body = call(server + f"api/export/{view['id']}.exe")
    assert status == 400 and "cannot download .exe" in body["error"]
    assert call(server + "api/search?q=walk")[1]["error"].startswith("no index was given")


def test_search_finds_the_take_of_an_index(tmp_path):
    pytest.importorskip("transformers", reason="the retrieval model reads MiniLM")
    from motionlang.api import index
    from motionlang.web.app import running
    from motionlang.web.studio import Studio
    folder = tmp_path / "lib"
    folder.mkdir()
    write(RIGS["mixamo"], folder, "walker", T=90)
    index(folder, tmp_path / "lib.idx", show_progress=False)
    studio = Studio(ServeOptions(**SMALL, index=str(tmp_path / "lib.idx")))
    with running(studio) as url:
        status, hits = call(url + "api/search?q=a%20person%20walks&k=3")
        assert status == 200 and hits and hits[0]["file"].startswith("walker")
        h = hits[0]
        status, view = call(url + f"api/take?file={h['file']}&start={h['start']}&end={h['end']}")
        assert status == 200 and view["n_joints"] == 21 and view["n_frames"] > 10


@pytest.mark.parametrize("name, expected", [
    ("LK", "L"), ("RMrot", "R"), ("BUN", ""), ("LeftUpLeg", "L"), ("RightHand", "R"),
    ("l_hip", "L"), ("upperarm_r", "R"), ("joint_LeftKnee", "L"), ("lfemur", "L"),
    ("rhumerus", "R"), ("LowerBack", ""), ("lowerback", ""), ("Hips", ""),
    ("mixamorig:LeftArm", "L"), ("Neck1", "")])
def test_sides_of_joint_names(name, expected):
    assert side(name) == expected


@pytest.mark.parametrize("fps, step", [(12.5, 1), (30, 1), (60, 2), (100, 4), (120, 4)])
def test_the_page_gets_at_most_view_fps(fps, step):
    assert view_step(fps) == step and fps / step <= VIEW_FPS


def test_a_fault_of_the_server_is_one_line_without_a_trace(tmp_path):
    from motionlang.web.app import running
    from motionlang.web.studio import Studio
    studio = Studio(ServeOptions(**SMALL))

    def broken(*args, **kwargs):
        raise RuntimeError("a bug with a secret path /home/someone")

    studio.generate = broken
    with running(studio) as url:
        status, body = post_json(url + "api/generate", {"text": "a person walks"})
    assert status == 500 and body["error"].startswith("internal error (RuntimeError)")
    assert "/home/someone" not in body["error"]


def test_a_describe_model_that_does_not_describe_is_refused_at_start():
    from motionlang.errors import MotionlangError
    from motionlang.web.studio import Studio
    with pytest.raises(MotionlangError, match="l2m"):
        Studio(ServeOptions(**{**SMALL, "describe_model": "l2m-procedural"}))


@pytest.mark.parametrize("host, local", [("127.0.0.1", True), ("127.0.0.2", True),
                                         ("::1", True), ("localhost", True),
                                         ("0.0.0.0", False), ("192.168.1.20", False),
                                         ("example.org", False)])
def test_only_loopback_hosts_count_as_local(host, local):
    assert ServeOptions(host=host).local is local


def test_serve_options_are_checked_as_one_line(capsys):
    assert main(["serve", "--port", "70000"]) == 2
    assert "--port must be in 0..65535" in capsys.readouterr().err
    assert main(["serve", "--max-upload-mb", "0"]) == 2
    assert "--max-upload-mb" in capsys.readouterr().err


def test_serve_with_a_missing_index_is_one_line(capsys, tmp_path):
    code = main(["serve", "--model", "l2m-procedural", "--describe-model", "m2l-procedural",
                 "--index", str(tmp_path / "none.idx"), "--port", "0"])
    err = capsys.readouterr().err
    assert code == 2 and "none.idx" in err and err.count("\n") == 1, err


def test_serve_help_needs_no_web_library():
    import subprocess
    code = ("import sys; sys.modules['fastapi'] = None; sys.modules['torch'] = None\n"
            "from motionlang.cli.main import main; sys.exit(main(['serve', '-h']))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=Path(__file__).parent)
    assert out.returncode == 0, out.stderr
    assert "--index FILE" in out.stdout and "127.0.0.1" in out.stdout


def test_generated_view_is_small_json(server):
    _, view = post_json(server + "api/generate", {"text": "a person runs", "seconds": 10})
    assert view["n_frames"] == 125
    assert len(json.dumps(view)) < 200_000   # ten seconds: a few tens of kilobytes


def test_the_command_serves_until_ctrl_c(tmp_path):
    """``motionlang serve --port 0`` prints where it listens, answers there, and Ctrl-C
    stops it with exit 0 and nothing written where it ran."""
    import signal
    import subprocess
    code = "import sys; from motionlang.cli.main import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen(
        [sys.executable, "-c", code, "serve", "--port", "0", "--model", "l2m-procedural",
         "--describe-model", "m2l-procedural"], cwd=tmp_path, text=True,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        line = proc.stdout.readline()
        assert line.startswith("motionlang serve: open http://127.0.0.1:"), line
        url = line.split()[3]
        status, info = call(url + "api/info")
        assert status == 200 and info["models"][0]["name"] == "l2m-procedural"
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert list(tmp_path.iterdir()) == []


def test_a_rig_no_map_fits_is_told_to_bring_its_joint_map_and_then_works(server, tmp_path):
    robot = write(RIGS["mixamo"], tmp_path, "robot", T=40)
    text = robot.read_text().replace("mixamorig:", "part_")   # names no map knows
    text = text.replace("part_Left", "part_A").replace("part_Right", "part_B")
    robot.write_text(text)
    status, body = post_files(server + "api/describe", [(robot.name, robot.read_bytes())])
    assert status == 400 and "upload its joint map (.json) with the file" in body["error"]
    assert "--joint-map" not in body["error"]
    side = {"L": "A", "R": "B"}
    joints = {"root": "Hips", "BP": "Spine", "BT": "Spine1", "BLN": "Neck", "BUN": "Head"}
    for s in "LR":
        joints |= {f"{s}S": f"{side[s]}Arm", f"{s}E": f"{side[s]}ForeArm",
                   f"{s}W": f"{side[s]}Hand", f"{s}H": f"{side[s]}UpLeg",
                   f"{s}K": f"{side[s]}Leg", f"{s}A": f"{side[s]}Foot",
                   f"{s}MRot": f"{side[s]}ToeBase", f"{s}F": f"{side[s]}Toe_End"}
    joint_map = {"joints": {k.replace("MRot", "Mrot"): "part_" + v for k, v in joints.items()}}
    files = [(robot.name, robot.read_bytes()), ("robot.json", json.dumps(joint_map).encode())]
    status, view = post_files(server + "api/describe", files)
    assert status == 200 and view["sentences"], view
    status, got = post_files(server + "api/rig", files)
    assert status == 200 and got["name"] == "robot", got


# ------------------------------------------------------------------ other sites
def test_a_foreign_host_is_refused(server):
    """DNS rebinding: a page of attacker.example whose name resolves to 127.0.0.1."""
    for path in ("", "api/info"):
        status, body = call(server + path, headers={"Host": "attacker.example:8000"})
        assert status == 400 and "attacker.example" in body["error"], body
    port = server.rsplit(":", 1)[1].strip("/")
    for name in (f"localhost:{port}", f"127.0.0.1:{port}", "localhost"):
        assert call(server + "api/info", headers={"Host": name})[0] == 200, name


def test_a_post_from_another_site_is_refused(server):
    body = json.dumps({"text": "a person walks", "seconds": 1}).encode()
    for headers in ({"Origin": "http://attacker.example"}, {"Origin": "null"},
                    {"Sec-Fetch-Site": "cross-site"}):
        status, reply = call(server + "api/generate", body,
                             {"Content-Type": "application/json", **headers})
        assert status == 403 and ("another site" in reply["error"] or
                                  "cross-site" in reply["error"]), (headers, reply)
    status, files = call(server + "api/describe", b"--x--\r\n",
                         {"Content-Type": "multipart/form-data; boundary=x",
                          "Origin": "http://attacker.example"})
    assert status == 403
    # the server's own page, and scripts that send neither header, are served
    own = server.rstrip("/")
    for headers in ({"Origin": own}, {"Sec-Fetch-Site": "same-origin"}, {}):
        status, reply = call(server + "api/generate", body,
                             {"Content-Type": "application/json", **headers})
        assert status == 200, (headers, reply)


def test_the_names_a_server_answers_to():
    from motionlang.web.same_site import _host_name, hosts_for
    assert hosts_for("127.0.0.1") == {"localhost", "127.0.0.1", "::1"}
    assert "myhost" in hosts_for("myhost") and hosts_for("0.0.0.0") is None
    assert "192.168.1.5" in hosts_for("192.168.1.5")
    assert [_host_name(h) for h in ("[::1]:8000", "LocalHost:80", "::1", "a.b")] == \
        ["::1", "localhost", "::1", "a.b"]


def test_serve_checks_its_address_before_loading_models(capsys):
    import socket
    assert main(["serve", "--host", "999.1.1.1"]) == 2
    err = capsys.readouterr().err
    assert "--host 999.1.1.1" in err and len(err.strip().splitlines()) == 1
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert main(["serve", "--port", str(port)]) == 2
        assert f"--port {port}" in capsys.readouterr().err


def test_a_take_declaring_a_wrong_rate_is_described_at_its_bodys_with_a_note(server,
                                                                            tmp_path):
    from motionlang.formats import write_motion
    from motionlang.rendering.output import body_motion
    from test_rate_hint import _jumps
    motion, _ = body_motion(_jumps(120.0), 120.0)
    path = tmp_path / "jump.bvh"
    write_motion(motion.replace(fps=25.0), path)   # 120 Hz frames, a 25 Hz header
    status, view = post_files(server + "api/describe", [(path.name, path.read_bytes())])
    assert status == 200, view
    assert view["seconds"] == pytest.approx(4.0, abs=0.05)   # 19.2 s at the header's rate
    assert len(view["notes"]) == 1
    assert view["notes"][0].startswith("jump.bvh: its header says 25 Hz") and \
        view["notes"][0].endswith("read at 120 Hz")   # no command-line flag on a page
    bvh = write(RIGS["mixamo"], tmp_path, T=40)
    assert post_files(server + "api/describe", [(bvh.name, bvh.read_bytes())])[1]["notes"] == []

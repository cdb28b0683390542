"""Proof in Blender: the BVH and the GLB that motionlang writes, imported by Blender's own
importers (headless), put every joint where motionlang's forward kinematics puts it, at
every frame, at the same frame rate, under the same names.

For each rig (the 21-joint body as ``generate`` writes it, a Bandai Namco take, that take
retargeted onto the Bandai rig as ``generate --rig`` writes it, the CMU subject-35 ASF/AMC
trial, a cmu_dev BVH where present) the motion is written with ``write_motion`` as ``.bvh``
and ``.glb``, Blender imports both (``blender_probe.py``, one Blender process) and the
world position of every joint at every frame is compared with ``Motion.positions()``:

* BVH: Blender's importer with its defaults (forward -Z, up Y: a Y-up file becomes Z-up,
  Blender ``(x, y, z)`` = file ``(x, -z, y)``), ``global_scale`` = metres per file unit, the
  scene's rate from the file (``update_scene_fps``), keys from frame 1. A joint is the
  head of the bone of its name; an End Site (a leaf without channels, which the importer
  makes no bone of) is the tail of its parent's bone.
* GLB: Blender's glTF importer (metres, Y up turned Z up the same way), keys at
  ``time x scene fps`` from frame 0; every joint, End Sites included, is a bone.

Run: .venv/bin/python benchmarks/blender_check.py [--frames N] [--markdown]
(needs ``blender`` on PATH: ``apt-get install -y blender python3-numpy`` on Debian 12).
"""
from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _common import DATA  # noqa: E402

from motionlang.formats import read_motion, write_motion  # noqa: E402
from motionlang.kinematics.motion import Motion  # noqa: E402

TOLERANCE_MM = 1.0
BANDAI = Path("/tmp/bandai/Bandai-Namco-Research-Motiondataset-1/data/"
              "dataset-1_walk_normal_001.bvh")
CMU_DEV = Path("/tmp/cmudev/cmu-dev/secondlife")


def _z_up_to_y_up(p: np.ndarray) -> np.ndarray:
    """Blender world (x, y, z), Z up -> motionlang's canonical (x, z, -y), Y up."""
    return np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)


def end_sites(motion: Motion) -> set[int]:
    """Joints a BVH file holds as End Sites: leaves without DOFs."""
    sk = motion.skeleton
    parents = set(sk.parents.tolist())
    return {j for j, joint in enumerate(sk.joints) if joint.ndof == 0 and j not in parents}


def run_blender(items: list[dict], workdir: Path, blender: str = "blender",
                timeout: float = 600) -> dict:
    """Run ``blender_probe.py`` on ``items`` (its JOB entries) in one headless Blender."""
    job, out = workdir / "job.json", workdir / "blender.json"
    job.write_text(json.dumps({"files": items}), encoding="utf-8")
    proc = subprocess.run([blender, "-b", "--factory-startup", "--python",
                           str(HERE / "blender_probe.py"), "--", str(job), str(out)],
                          capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0 or not out.is_file():
        tail = "\n".join((proc.stdout + proc.stderr).splitlines()[-15:])
        raise RuntimeError(f"blender failed (exit {proc.returncode}):\n{tail}")
    return json.loads(out.read_text(encoding="utf-8"))


def compare(motion: Motion, got: dict, fmt: str, scale: float = 1.0) -> dict:
    """One row of the table: what Blender made of ``motion`` written as ``fmt`` (a BVH
    imported with ``global_scale`` = ``scale`` metres per file unit).

    An End Site of (nearly) zero length is not compared: the importer lengthens a bone
    whose tail would sit on its head (to a tenth of a file unit), so that tail is no
    longer the site, which sits on its parent's head, compared already."""
    sk = motion.skeleton
    expected = motion.positions()
    index = {n: i for i, n in enumerate(got["names"])}
    heads = _z_up_to_y_up(np.asarray(got["heads"], float))
    tails = _z_up_to_y_up(np.asarray(got["tails"], float))
    ends = end_sites(motion) if fmt == "bvh" else set()
    missing, cols, ours = [], [], []
    for j, name in enumerate(sk.names):
        if j in ends:
            bone = index.get(sk.names[sk.joints[j].parent])
            long = np.linalg.norm(sk.joints[j].offset) > 0.001 * scale
            if bone is not None and not got["children"][bone] and long:
                cols.append(tails[:, bone])
                ours.append(j)
            continue
        if name not in index:
            missing.append(name)
            continue
        cols.append(heads[:, index[name]])
        ours.append(j)
    T = len(got["frames"])
    first = 1 if fmt == "bvh" else 0
    frames_equal = T == motion.n_frames and \
        np.allclose(got["frames"], np.arange(first, first + T), atol=1e-3)
    err = np.zeros((1, 1))
    if frames_equal and cols:
        err = np.linalg.norm(np.stack(cols, axis=1) - expected[:, ours], axis=-1) * 1000
    return {"format": fmt, "joints": len(sk), "compared": len(ours), "missing": missing,
            "frames": T, "frames_equal": bool(frames_equal), "fps": float(got["fps"]),
            "fps_equal": abs(got["fps"] / motion.fps - 1) < 1e-4,
            "max_mm": float(err.max()), "mean_mm": float(err.mean()),
            "extra_bones": sorted(set(got["names"]) - set(sk.names))}


def check(motions: dict[str, Motion], workdir: Path, blender: str = "blender") -> list[dict]:
    """Write each motion as BVH and GLB into ``workdir``, import them all in Blender and
    compare; one row per (motion, format), with ``ok`` when all holds."""
    items, scales = [], {}
    for key, motion in motions.items():
        for ext in (".bvh", ".glb"):
            path = write_motion(motion, workdir / f"{key}{ext}")
            scale = read_motion(path).skeleton.file_unit if ext == ".bvh" else 1.0
            scales[f"{key}{ext}"] = scale
            items.append({"id": f"{key}{ext}", "path": str(path), "scale": scale,
                          "format": "bvh" if ext == ".bvh" else "gltf",
                          "fps": float(motion.fps)})
    found = run_blender(items, workdir, blender)
    rows = []
    for key, motion in motions.items():
        for fmt, ext in (("bvh", ".bvh"), ("glb", ".glb")):
            row = {"rig": key, "fps_motion": float(motion.fps),
                   **compare(motion, found[f"{key}{ext}"], fmt, scales[f"{key}{ext}"])}
            row["ok"] = (not row["missing"] and row["frames_equal"] and row["fps_equal"]
                         and row["compared"] > 0 and row["max_mm"] <= TOLERANCE_MM)
            rows.append(row)
    return rows


def default_motions(frames: int | None) -> dict[str, Motion]:
    """The rigs of the check, from the real data that is present."""
    from motionlang.features.joint_map import positions21
    from motionlang.rendering.output import body_motion

    out: dict[str, Motion] = {}
    if BANDAI.is_file():
        take = read_motion(BANDAI)
        p21 = positions21(take)
        out["body21"] = body_motion(p21, take.fps, name="body21")[0]
        out["bandai"] = take
        out["bandai_retargeted"] = body_motion(p21, take.fps, take, name="bandai_rt")[0]
    amc = DATA / "cmu35" / "35_01.amc"
    if amc.is_file():
        out["cmu35_asf_amc"] = read_motion(amc)
    dev = sorted(CMU_DEV.glob("*.bvh")) if CMU_DEV.is_dir() else []
    if dev:
        out[f"cmu_dev_{dev[0].stem}"] = read_motion(dev[0])
    if frames:
        out = {k: m[:frames] for k, m in out.items()}
    return out


def table(rows: list[dict]) -> str:
    head = ("| rig | file | joints (compared) | frames | fps: motion / Blender | names kept "
            "| max error mm | mean error mm | ok |\n|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        names = "yes" if not r["missing"] else f"no: {', '.join(r['missing'][:4])}"
        lines.append(
            f"| {r['rig']} | {r['format']} | {r['joints']} ({r['compared']}) | {r['frames']}"
            f"{'' if r['frames_equal'] else ' (differs)'} | {r['fps_motion']:g} / "
            f"{r['fps']:.5g} | {names} | {r['max_mm']:.4f} | {r['mean_mm']:.4f} | "
            f"{'yes' if r['ok'] else 'NO'} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=None, help="only the first N frames")
    ap.add_argument("--blender", default=shutil.which("blender"), help="Blender executable")
    ap.add_argument("--keep", default=None, help="keep the files written in this folder")
    args = ap.parse_args()
    if not args.blender:
        sys.exit("blender_check: no blender on PATH (apt-get install -y blender python3-numpy)")
    motions = default_motions(args.frames)
    if not motions:
        sys.exit("blender_check: none of the real data files are present")
    version = subprocess.run([args.blender, "--version"], capture_output=True,
                             text=True).stdout.splitlines()[0]
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(args.keep) if args.keep else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        rows = check(motions, work, args.blender)
    print(f"{version}; tolerance {TOLERANCE_MM} mm\n")
    print(table(rows))
    extra = {r["rig"]: r["extra_bones"] for r in rows if r["extra_bones"]}
    if extra:
        print(f"\nBlender bones that are not motionlang joints: {extra}")
    sys.exit(0 if all(r["ok"] for r in rows) else 1)


if __name__ == "__main__":
    main()

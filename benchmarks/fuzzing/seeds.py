"""Valid files that fuzzing starts from: small hand-made ones (every machine) and real ones
cut to a few frames (where ``../shared/data`` exists), so that one reading takes
milliseconds.

:func:`seeds` returns ``(data, skeleton)`` pairs: ``skeleton`` is the ASF text an AMC is read
with, None for the other formats.

HumanML3D-layout folders (format ``h3d``) travel as an uncompressed tar of the folder's
files under one top folder named after the body (``kit/new_joints/000001.npy``...):
:func:`h3d_files` builds a tiny one, :func:`pack_h3d` / :func:`unpack_h3d` convert.
"""
from __future__ import annotations

import io
import re
import tarfile
from pathlib import Path

import numpy as np

TINY_ASF = b"""# two bones up the Y axis and two arms
:version 1.10
:name tiny
:units
  mass 1.0
  length 1.0
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name chest
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx ry rz
    limits (-180 180)
           (-180 180)
           (-180 180)
  end
  begin
     id 2
     name larm
     direction 1 0 0
     length 5
     axis 0 0 90 XYZ
    dof rx
  end
  begin
     id 3
     name rarm
     direction -1 0 0
     length 5
     axis 0 0 -90 XYZ
    dof rx
  end
:hierarchy
  begin
    root chest
    chest larm rarm
  end
"""

TINY_BVH = b"""HIERARCHY
ROOT Hips
{
  OFFSET 0 90 0
  CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    JOINT LeftLeg
    {
      OFFSET 0 -45 0
      CHANNELS 2 Xrotation Zrotation
      End Site
      {
        OFFSET 0 -45 0
      }
    }
  }
  JOINT Chest
  {
    OFFSET 0 30 0
    CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
    End Site
    {
      OFFSET 0 50 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
1 2 3 90 0 0 0 0 0 90 0 0 30 0 0 0 0
1.5 2 3.25 10.5 -20 30 5 6 7 -80 0 0 30 0 1 2 3
2 2 3.5 -170 89 179 -5 -6 -7 100 0 0 30 0 -1 -2 -3
"""


def tiny_amc(frames: int = 3) -> bytes:
    """AMC text for :data:`TINY_ASF`."""
    out = [":FULLY-SPECIFIED", ":DEGREES"]
    for i in range(1, frames + 1):
        out += [str(i), f"root {i} 2 3 4 5 6", "chest 10 20 30", f"larm {40 + i}", "rarm 50"]
    return ("\n".join(out) + "\n").encode()


def tiny_mmm(frames: int = 3) -> bytes:
    """An MMM XML text with two joint DOFs."""
    body = "".join(
        f"<MotionFrame>\n<Timestep>{i / 100:.2f}</Timestep>\n<RootPosition>0 0 900"
        f"</RootPosition>\n<RootRotation>0 0 {i / 10}</RootRotation>\n<JointPosition>-0.{i} "
        f"0.5 </JointPosition>\n</MotionFrame>\n" for i in range(frames))
    return (f"<?xml version='1.0'?>\n<MMM>\n<Motion name='tiny'>\n<Model><File>mmm.xml</File>"
            f"</Model>\n<ModelProcessorConfig type='Winter'><Height>1.7</Height>"
            f"</ModelProcessorConfig>\n<JointOrder>\n<Joint name='LKx_joint'/>\n"
            f"<Joint name='RKx_joint'/>\n</JointOrder>\n<MotionFrames>\n{body}</MotionFrames>"
            f"\n</Motion>\n</MMM>\n").encode()


def mit_tree(n: int = 2) -> list[dict]:
    """Node fields of an ``n``-node chain in Taylor's layout (6 columns per node)."""
    return [{"children": np.array([[i + 2.0]]) if i < n - 1 else np.zeros((0, 0)),
             "parent": np.zeros((0, 0)) if i == 0 else np.array([[float(i)]]),
             "or": np.array([[6.0 * i + 1, 6 * i + 2, 6 * i + 3]]),
             "offset": np.array([[6.0 * i + 4, 6 * i + 5, 6 * i + 6]])} for i in range(n)]


def mit_sequence(T: int = 4, n: int = 2) -> np.ndarray:
    X = np.zeros((T, 6 * n))
    X[:, 0:2] = np.pi / 2   # a standing root
    X[:, 5] = 900.0
    X[:, 11::6] = -400.0    # every bone 400 mm down
    if n > 1:
        X[:, 6] = np.linspace(0, 0.5, T)  # a swinging hip
    return X


def write_mit(tree: list[dict], sequences, compress: bool = False,
              skel_extra: dict | None = None) -> bytes:
    """MAT-file bytes (scipy's writer) of ``skel.tree`` = ``tree`` (field dicts; any value
    types) and ``Motion`` = a 1 x n cell of ``sequences`` (a list; anything else is
    written as it is)."""
    import scipy.io as sio

    names = sorted({k for node in tree for k in node}) or ["parent"]
    nodes = np.zeros((1, len(tree)), dtype=[(k, "O") for k in names])
    for i, node in enumerate(tree):
        for k in names:
            nodes[0, i][k] = node.get(k, np.zeros((0, 0)))
    fields = {"tree": nodes, "type": "mit", **(skel_extra or {})}
    skel = np.zeros((1, 1), dtype=[(k, "O") for k in fields])
    for k, v in fields.items():
        skel[0, 0][k] = v
    cells = sequences
    if isinstance(sequences, list):
        cells = np.empty((1, len(sequences)), dtype=object)
        for i, s in enumerate(sequences):
            cells[0, i] = s
    buf = io.BytesIO()
    sio.savemat(buf, {"skel": skel, "Motion": cells}, do_compression=compress)
    return buf.getvalue()


# a KIT stick body standing at attention (mm), as in tests/test_humanml3d.py
_STAND = np.stack([
    [0, 0, 0, 0, 0, 200, 200, 200, -200, -200, -200, 100, 100, 100, 100, 100, -100, -100,
     -100, -100, -100],
    [900, 1000, 1100, 1400, 1500, 1400, 1100, 850, 1400, 1100, 850, 900, 500, 100, 100, 100,
     900, 500, 100, 100, 100],
    [0] * 14 + [60, 160] + [0] * 3 + [60, 160]], axis=1).astype(float)
_SMPL_FROM_KIT = [0, 11, 16, 1, 12, 17, 2, 13, 18, 3, 14, 19, 3, 5, 8, 4, 5, 8, 6, 9, 7, 10]


def h3d_walk(T: int, body: str = "kit") -> np.ndarray:
    """(T, J, 3) joints of a stick body walking and turning, in the body's file unit."""
    out = []
    for t in range(T):
        c, s = np.cos(0.02 * t), np.sin(0.02 * t)
        rel = (_STAND - _STAND[0]) @ np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
        out.append(rel + _STAND[0] + [0, 0, 60.0 * t])
    p = np.stack(out)
    if body == "smpl":
        p = p[:, _SMPL_FROM_KIT] / 1000.0
        p[:, [12, 13, 14], 1] += 0.03
        p[:, 15, 1] += 0.05
    return p


def npy_bytes(array) -> bytes:
    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=True)
    return buf.getvalue()


def h3d_files(body: str = "kit", frames: int = 6, ids=("000001", "M000001"),
              captions: bytes | None = None) -> dict[str, bytes]:
    """A tiny HumanML3D-layout folder: relative path -> bytes."""
    from motionlang.features.h3d_vectors import H3D_BODIES, joints_to_vectors, mirror_joints
    spec = H3D_BODIES[body]
    p = h3d_walk(frames, body)
    files: dict[str, bytes] = {}
    every = []
    for i, mid in enumerate(ids):
        rows, layout = joints_to_vectors(mirror_joints(p, spec) if i % 2 else p, spec)
        files[f"new_joint_vecs/{mid}.npy"] = npy_bytes(rows.astype(np.float32))
        files[f"new_joints/{mid}.npy"] = npy_bytes(layout[:-1].astype(np.float32))
        files[f"texts/{mid}.txt"] = captions or (
            b"a person walks forward#a/DET person/NOUN walk/VERB forward/ADV#0.0#0.0\n"
            b"someone takes a step#someone/PRON#0.0#0.2\n")
        every.append(rows)
    rows = np.concatenate(every)
    files["Mean.npy"] = npy_bytes(rows.mean(0).astype(np.float32))
    files["Std.npy"] = npy_bytes((rows.std(0) + 1).astype(np.float32))
    files["train.txt"] = ("\n".join(ids) + "\n").encode()
    files["val.txt"], files["test.txt"] = b"", b"000002\n"
    return files


def pack_h3d(files: dict[str, bytes], body: str = "kit") -> bytes:
    """An uncompressed tar of ``files`` under the folder ``body``."""
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w", format=tarfile.PAX_FORMAT) as tf:
        for name, data in files.items():
            info = tarfile.TarInfo(f"{body}/{name}")
            info.size, info.mtime = len(data), 0
            tf.addfile(info, io.BytesIO(data))
    return buf.getvalue()


def unpack_h3d(data: bytes) -> tuple[str, dict[str, bytes]]:
    """(body, files) of :func:`pack_h3d`'s bytes: only regular files whose names stay in the
    folder (no ``..``, not absolute); body ``kit`` unless it says ``smpl``."""
    body, files = "kit", {}
    try:
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:") as tf:
            for info in tf:
                parts = info.name.split("/")
                if not info.isfile() or len(parts) < 2 or info.name.startswith("/") \
                        or any(x in ("", ".", "..") for x in parts):
                    continue
                body = "smpl" if parts[0] == "smpl" else "kit"
                files["/".join(parts[1:])] = tf.extractfile(info).read()
    except (tarfile.TarError, EOFError, OSError, ValueError):
        pass  # what was read so far
    return body, files


def _cut(text: bytes, start: bytes, frames: int) -> bytes:
    """``text`` without the frames after the first ``frames`` (blocks starting ``start``)."""
    hits = [m.start() for m in re.finditer(start, text, re.MULTILINE)]
    return text[:hits[frames]] if len(hits) > frames else text


def _real(fmt: str, shared: Path) -> list[tuple[bytes, bytes | None]]:
    out: list[tuple[bytes, bytes | None]] = []
    asf35, amc35 = shared / "cmu35/35.asf", shared / "cmu35/35_01.amc"
    if fmt == "asf":
        out += [(p.read_bytes(), None) for p in (asf35, shared / "cmu49/49.asf") if p.is_file()]
    elif fmt == "amc" and asf35.is_file() and amc35.is_file():
        out.append((_cut(amc35.read_bytes(), rb"^\d+\s*$", 3), asf35.read_bytes()))
    elif fmt == "mmm" and (shared / "kitml/00001_mmm.xml").is_file():
        xml = (shared / "kitml/00001_mmm.xml").read_bytes()
        ends = [m.end() for m in re.finditer(rb"</MotionFrame>\s*", xml)]
        tail = xml.index(b"</MotionFrames>")
        out.append((xml[:ends[2]] + xml[tail:], None))
    elif fmt == "bvh":
        tar = shared / "bandai/Bandai-Namco-Research-Motiondataset-1.tar.xz"
        if tar.is_file():
            with tarfile.open(tar) as tf:
                info = next(m for m in tf if m.name.endswith(".bvh"))
                text = tf.extractfile(info).read()
            head, frames = text.split(b"Frame Time:", 1)
            lines = frames.split(b"\n")
            out.append((head.replace(re.search(rb"Frames:\s*\d+", head).group(), b"Frames: 3")
                        + b"Frame Time:" + b"\n".join(lines[:4]) + b"\n", None))
    elif fmt == "mit" and (shared / "mit/motion.mat").is_file():
        from motionlang.formats.matfile import read_mat
        data = read_mat(shared / "mit/motion.mat")
        tree = list(data["skel"][0, 0]["tree"].ravel())
        seqs = [data["Motion"][0, 0][:3], data["Motion"][0, 1][:2]]
        out += [(write_mit(tree, seqs), None), (write_mit(tree, seqs[:1], compress=True), None)]
    return out


def seeds(fmt: str, shared: str | Path | None = None) -> list[tuple[bytes, bytes | None]]:
    """Hand-made and (if ``shared`` is the real-data folder) real seeds of format ``fmt``."""
    from .sidecars import SIDECARS, sidecar_seeds
    if fmt in SIDECARS:
        return [(data, None) for data in sidecar_seeds(fmt)]
    hand = {"asf": [(TINY_ASF, None)], "amc": [(tiny_amc(), TINY_ASF)],
            "bvh": [(TINY_BVH, None)], "mmm": [(tiny_mmm(), None)],
            "mit": [(write_mit(mit_tree(), [mit_sequence(), mit_sequence(3)]), None)],
            "h3d": [(pack_h3d(h3d_files("kit"), "kit"), None),
                    (pack_h3d(h3d_files("smpl", 5, ("a1",)), "smpl"), None)]}[fmt]
    real = _real(fmt, Path(shared)) if shared is not None and Path(shared).is_dir() else []
    return hand + real


__all__ = ["TINY_ASF", "TINY_BVH", "tiny_amc", "tiny_mmm", "mit_tree", "mit_sequence",
           "write_mit", "h3d_walk", "h3d_files", "pack_h3d", "unpack_h3d", "npy_bytes",
           "seeds"]

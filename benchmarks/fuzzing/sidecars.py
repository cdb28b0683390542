"""Fuzz inputs beyond motion files: caption files (``captions`` CSV, ``captions-jsonl``),
joint maps (``jointmap``), checkpoints (``pt``: a torch model; ``npz``: a CRBM), library
indexes (``index``, what ``motionlang index`` writes) and glTF binaries (``glb``).

Seeds are made here, small (a tiny model, a two-take index), so that thousands of inputs
run in minutes; crafted inputs aim at what the second audit found (issue 44): JSON nested
200,000 deep, 5,000-digit numbers, NUL and control characters in names and captions, a
2 MB caption, unterminated quotes, byte-order marks, configs of the wrong type or asking
for 1e9 units, swapped or missing tensors, truncated archives.
"""
from __future__ import annotations

import functools
import io
import json
import tempfile
import zipfile
from pathlib import Path

from .edits import Choose, edit, pick

SIDECARS = ("captions", "captions-jsonl", "jointmap", "pt", "npz", "index", "glb")
EXTENSIONS = {"captions": ".csv", "captions-jsonl": ".jsonl", "jointmap": ".json",
              "pt": ".pt", "npz": ".npz", "index": ".idx", "glb": ".glb"}


# ------------------------------------------------------------------------ seeds
def _tiny_motion():
    from motionlang.datasets.synth.corpus import generate_sample
    m = generate_sample(0, 0).motion
    return m.replace(joint_angles=m.joint_angles[:6], root_translation=m.root_translation[:6],
                     root_rotation=m.root_rotation[:6])


@functools.cache
def sidecar_seeds(fmt: str) -> tuple[bytes, ...]:
    """Valid files of ``fmt`` (bytes), made once per process."""
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        if fmt == "captions":
            return (b"file,text\na.bvh,a person walks forward\nb.bvh,\"someone waves, then "
                    b"sits\"\n", "\ufefffile,text\nc.bvh,une personne marche\n".encode())
        if fmt == "captions-jsonl":
            return (b'{"file": "a.bvh", "text": "a person walks"}\n'
                    b'{"file": "b.bvh", "text": "someone jumps twice"}\n',)
        if fmt == "jointmap":
            from motionlang.features.joint_map import map_json, template_map
            return (map_json(template_map(_tiny_motion().skeleton)).encode(),)
        if fmt == "pt":
            return (_tiny_checkpoint(folder),)
        if fmt == "npz":
            from motionlang.models.crbm.config import CRBMConfig
            from motionlang.models.crbm.model import CRBM
            CRBM(CRBMConfig(n_hidden=4, order=2), 6).save(folder / "c.npz")
            return ((folder / "c.npz").read_bytes(),)
        if fmt == "index":
            return (_tiny_index(folder),)
        if fmt == "glb":
            from motionlang.formats import write_motion
            write_motion(_tiny_motion(), folder / "m.glb")
            return ((folder / "m.glb").read_bytes(),)
    raise ValueError(fmt)


def _tiny_checkpoint(folder: Path) -> bytes:
    """A small model file: an M2L of a few units on the 21-joint position features."""
    import numpy as np

    from motionlang.datasets.text import Vocabulary
    from motionlang.features.base import make_features
    from motionlang.features.normalizer import Normalizer
    from motionlang.models.seq2seq.config import M2LConfig
    from motionlang.models.seq2seq.m2l import MotionToLanguage
    feats = make_features("positions").fit([_tiny_motion()])
    dim = feats.dim
    vocab = Vocabulary.build(["a person walks", "someone waves"])
    model = MotionToLanguage(M2LConfig(n_features=dim, vocab_size=len(vocab.itos),
                                       enc_hidden=4, dec_hidden=4, embed_dim=4),
                             vocab=vocab, normalizer=Normalizer(np.zeros(dim), np.ones(dim)),
                             features=feats)
    model.save(folder / "m.pt")
    return (folder / "m.pt").read_bytes()


def _tiny_index(folder: Path) -> bytes:
    """``motionlang index`` of two short takes with the packaged default model."""
    from motionlang.api import index
    from motionlang.formats import write_motion
    (folder / "takes").mkdir()
    write_motion(_tiny_motion(), folder / "takes" / "a.bvh")
    write_motion(_tiny_motion(), folder / "takes" / "b.bvh")
    index(folder / "takes", folder / "x.idx")
    return (folder / "x.idx").read_bytes()


# ------------------------------------------------------------------------ inputs
def mutate_sidecar(data: bytes, choose: Choose, fmt: str) -> bytes:
    """1-3 byte-level edits; for zip-based files (``pt``, ``npz``, ``index``) edits of one
    member's bytes, the archive rebuilt around it half of the time (so that the CRC matches
    and the content checks are reached)."""
    if fmt in ("pt", "npz", "index") and choose(2):
        return _edit_member(data, choose)
    ops = ["truncate", "flip", "delete", "duplicate", "swap", "number", "number", "token",
           "garbage", "repeat"]
    for _ in range(1 + choose(3)):
        data = edit(data, pick(choose, ops), choose)
    return data


def _edit_member(data: bytes, choose: Choose) -> bytes:
    try:
        src = zipfile.ZipFile(io.BytesIO(data))
        names = src.namelist()
    except (zipfile.BadZipFile, ValueError, OSError):
        return data
    victim = names[choose(len(names))]
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as dst:
        for name in names:
            body = src.read(name)
            if name == victim:
                ops = ["truncate", "flip", "number", "token", "garbage", "delete"]
                body = edit(body, pick(choose, ops), choose)
            dst.writestr(src.getinfo(name), body)
    return out.getvalue()


def crafted_sidecar(fmt: str, choose: Choose) -> bytes:
    """An input aimed at one weakness of ``fmt``'s reader."""
    depth = [10, 1000, 200_000][choose(3)]
    deep = ("[" * depth + "]" * depth).encode()
    big = ("9" * [30, 5000, 100_000][choose(3)]).encode()
    if fmt == "captions":
        return pick(choose, [
            b"file,text\na.bvh,\"never closed\nb.bvh,next\n" * (1 + choose(50)),
            b"file,text\na\x00.bvh,NUL in a name\n",
            b"file,text\na.bvh,a \x07 bell\n",
            b"file,text\na.bvh," + b"word " * (400_000 + choose(10)) + b"\n",
            b"file,text\n" + b"".join(b"f%d.bvh,w%d\n" % (i, i) for i in range(20_000)),
            b"file,text\n" + b"a.bvh," + big + b"\n",
            b"\xff\xfef\x00i\x00l\x00e\x00",
            b"text,file\na.bvh,swapped header\n"])
    if fmt == "captions-jsonl":
        return pick(choose, [
            b'{"file": "a.bvh", "text": ' + deep + b"}\n",
            b"\xef\xbb\xbf" + sidecar_seeds("captions-jsonl")[0],
            b'{"file": "a\\u0000.bvh", "text": "NUL"}\n',
            b'{"file": "a.bvh", "text": ' + big + b"}\n",
            b'{"file": "a.bvh", "text": "' + b"w " * 1_000_000 + b'"}\n',
            b'["file", "text"]\n', b'{"file": "a.bvh"'])
    if fmt == "jointmap":
        seed = json.loads(sidecar_seeds("jointmap")[0])
        return pick(choose, [
            deep, b"\xef\xbb\xbf" + sidecar_seeds("jointmap")[0],
            json.dumps({**seed, "name": "x\u0000y"}).encode(),
            json.dumps({**seed, "map": {"pelvis": float("nan")}}).encode(),
            json.dumps({**seed, "weights": big.decode()}).encode(),
            json.dumps({"map": {"pelvis": {"a": 1e308}}}).encode(),
            json.dumps({**seed, "map": "pelvis"}).encode(), big])
    return mutate_sidecar(sidecar_seeds(fmt)[0], choose, fmt)


# ------------------------------------------------------------------------ the child's side
def read_sidecar(fmt: str, path: str):
    """Read ``path`` as ``fmt`` with motionlang's one reader of it; returns what it gives."""
    if fmt in ("captions", "captions-jsonl"):
        from motionlang.datasets.custom import read_captions
        return read_captions(path)
    if fmt == "jointmap":
        from motionlang.features.joint_map import load_joint_map
        return load_joint_map(path)
    if fmt in ("pt", "npz"):
        from motionlang.models.registry import load_model
        return load_model(path)
    if fmt == "index":
        from motionlang.library.store import load_index
        return load_index(path)
    if fmt == "glb":
        from motionlang.formats.gltf_read import read_gltf_animation
        return read_gltf_animation(path)
    raise ValueError(fmt)


__all__ = ["SIDECARS", "EXTENSIONS", "sidecar_seeds", "mutate_sidecar", "crafted_sidecar",
           "read_sidecar"]

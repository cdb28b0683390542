"""A small KIT-ML release zip (a real motion, a made-up long one and an unannotated one)."""
from __future__ import annotations

import io
import json
import zipfile


def tiny_mmm(n_frames: int) -> bytes:
    """A made-up MMM file: two joints, ``n_frames`` frames at 100 Hz."""
    frames = "".join(
        f"<MotionFrame><Timestep>{i / 100:.2f}</Timestep><RootPosition>0 0 900</RootPosition>"
        f"<RootRotation>0 0 0</RootRotation><JointPosition>0 0 </JointPosition></MotionFrame>\n"
        for i in range(n_frames))
    return (f"<?xml version='1.0'?>\n<MMM><Motion name='tiny'><Model><File>mmm.xml</File>"
            f"</Model><JointOrder><Joint name='LKx_joint'/><Joint name='RKx_joint'/></JointOrder>"
            f"<MotionFrames>\n{frames}</MotionFrames></Motion></MMM>\n").encode()


def build_release(real_mmm: bytes) -> bytes:
    """A small release zip: the real motion 00001, a made-up 31 s motion (filtered out)
    and a made-up 0.5 s motion without annotations, inside a top-level folder."""
    members = {
        "00001_mmm.xml": real_mmm,
        "00001_annotations.json": json.dumps(["A person walks forward.",
                                              "Someone takes a few steps."]).encode(),
        "00001_meta.json": json.dumps({"source": {"database": {"identifier": "kit"}}}).encode(),
        "00001_raw.c3d": b"\0" * 64,
        "00002_mmm.xml": tiny_mmm(3100),
        "00002_annotations.json": b'["A person stands still for a long time."]',
        "00002_meta.json": b"{}",
        "00007_mmm.xml": tiny_mmm(50),
        "00007_annotations.json": b"[]",
        "00007_meta.json": b"{}",
    }
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(f"2016-10-10/{name}", data)
    return buf.getvalue()

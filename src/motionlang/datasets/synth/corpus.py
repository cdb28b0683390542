"""The synthetic corpus on disk, in the KIT-ML release layout.

Per sample ``NNNNN`` (1-based, five digits): ``NNNNN_mmm.xml`` (MMM motion at 100 Hz,
written by :func:`motionlang.formats.mmm.write_mmm`), ``NNNNN_annotations.json`` (a JSON
list of 2-4 distinct sentences) and ``NNNNN_meta.json`` (ground truth: the primitives with
side, count, direction, speed, angle and frame range; what each sentence states; subject
height and mass; generator version and seed).

Every sample draws from its own RNG seeded by ``(seed, index)``, so a corpus is
byte-identical for a seed whatever the number of worker processes.
"""
from __future__ import annotations

import json
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.datasets.synth.compose import build_motion, random_program, random_style
from motionlang.datasets.synth.grammar import sentences
from motionlang.datasets.synth.spec import PARAM_FIELDS, Primitive
from motionlang.errors import MotionlangError
from motionlang.formats.mmm import write_mmm
from motionlang.kinematics.motion import Motion
from motionlang.utils.atomic import atomic_path, new_folder
from motionlang.utils.progress import progress

GENERATOR = "motionlang.datasets.synth"
#: samples of one corpus: far beyond any use, and a mistyped count fails before any work
MAX_SAMPLES = 1_000_000
#: Bump when the output for a given (seed, index) changes.
GENERATOR_VERSION = "1.0"


@dataclass
class SynthSample:
    """One generated sample.

    Attributes:
        id: "NNNNN". motion: 100 Hz MMM motion. annotations: 2-4 sentences.
        stated: per sentence, the primitives' parameters it states (None where unstated).
        primitives: ground truth with frame ranges. style: the per-sample variation.
    """

    id: str
    motion: Motion
    annotations: list[str]
    stated: list[list[Primitive]]
    primitives: list[Primitive]
    style: dict
    seed: int
    index: int

    def meta(self) -> dict:
        """The ``_meta.json`` content."""
        return {
            "source": {"database": "motionlang synthetic corpus", "generator": GENERATOR,
                       "generator_version": GENERATOR_VERSION, "seed": self.seed,
                       "index": self.index},
            "id": self.id, "fps": self.motion.fps, "n_frames": self.motion.n_frames,
            "duration_s": round(self.motion.duration, 2),
            "subject": {"height_m": self.style["height"], "mass_kg": self.motion.meta["mass"]},
            "primitives": [p.to_dict() for p in self.primitives],
            "annotation_params": [[{f: getattr(p, f) for f in PARAM_FIELDS} | {"layer": p.layer}
                                   for p in s] for s in self.stated],
            "style": self.style,
        }


def ground_truth(meta: dict) -> list[Primitive]:
    """The primitives (with frame ranges) stored in a sample's ``_meta.json`` dict."""
    return [Primitive.from_dict(d) for d in meta.get("primitives", [])]


def sample_rng(seed: int, index: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), int(index)])


def generate_sample(seed: int, index: int) -> SynthSample:
    """The ``index``-th sample (0-based) of the corpus of ``seed``."""
    rng = sample_rng(seed, index)
    program = random_program(rng)
    style = random_style(rng)
    motion, prims, _ = build_motion(program, style, rng)
    sid = f"{index + 1:05d}"
    motion = motion.replace(name=f"synth_{sid}")
    pairs = sentences(prims, rng, int(rng.integers(2, 5)))
    return SynthSample(sid, motion, [s for s, _ in pairs], [st for _, st in pairs], prims,
                       style, int(seed), int(index))


def write_sample(sample: SynthSample, out: str | Path) -> None:
    """Write the three KIT-ML files of one sample into ``out``."""

    out = Path(out)
    write_mmm(sample.motion, out / f"{sample.id}_mmm.xml", fsync=False)
    # small JSON files: atomic rename without fsync (thousands of them; fsync dominated)
    for suffix, obj, kw in (("annotations", sample.annotations, {"ensure_ascii": False}),
                            ("meta", sample.meta(), {"indent": 1})):
        with atomic_path(out / f"{sample.id}_{suffix}.json", sync=False) as tmp:
            tmp.write_text(json.dumps(obj, **kw), encoding="utf-8")


def _work(args: tuple[int, int, str]) -> str:
    seed, index, out = args
    s = generate_sample(seed, index)
    write_sample(s, out)
    return s.id


def write_corpus(out: str | Path, n: int, seed: int = 0, *, start: int = 0,
                 workers: int | None = None, show_progress: bool | None = None) -> list[str]:
    """Generate samples ``start .. start+n-1`` of ``seed`` into ``out``; returns their ids.

    Args:
        workers: processes (default: up to 2, the CPU count; never more than the CPU
            count, which is all they can use); 1 runs in this process.
    """
    out = Path(out)
    if not 1 <= n or start + n > MAX_SAMPLES:
        raise MotionlangError(f"a corpus holds 1..{MAX_SAMPLES:,} samples (start + n); "
                              f"got start {start:,} and n {n:,}")
    if workers is None:
        workers = 2
    workers = max(1, min(workers, os.cpu_count() or 1))
    jobs = ((int(seed), i, str(out)) for i in range(start, start + n))
    bar = progress(total=n, desc="synth", unit="motion",
                   disable=None if show_progress is None else not show_progress)
    ids = []
    # a stopped corpus is useless; one written into a new folder goes with it
    with new_folder(out, remove_files=True):
        try:
            if workers <= 1 or n < 8:
                for j in jobs:
                    ids.append(_work(j))
                    bar.update()
            else:
                with ProcessPoolExecutor(max_workers=workers) as pool:
                    chunk = max(1, min(32, n // (8 * workers)))
                    for sid in pool.map(_work, jobs, chunksize=chunk):
                        ids.append(sid)
                        bar.update()
        finally:
            bar.close()
    return ids

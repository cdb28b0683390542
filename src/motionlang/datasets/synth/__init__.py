"""Procedural KIT-style motion-language corpus with known ground truth.

Motions on the MMM skeleton (walk, run, turn, wave, kick, stomp, squat, jump, raise arms,
bow, wipe, punch, stand; sequences and upper-body overlays), 2-4 English sentences each
from a KIT-like grammar, the exact parameters in ``_meta.json``, a parameter extractor
for scoring generated descriptions, and augmentation (mirror, speed, concatenation).

Main entry points::

    from motionlang.datasets.synth import generate_sample, write_corpus, extract
    write_corpus("data/synth", n=1000, seed=0)     # = motionlang data synth
    extract("A person waves twice with the left hand.")
"""
from motionlang.datasets.synth.augment import (
                                               change_speed,
                                               concat_samples,
                                               mirror_sample,
                                               mirror_text,
)
from motionlang.datasets.synth.corpus import (
                                               GENERATOR_VERSION,
                                               SynthSample,
                                               generate_sample,
                                               ground_truth,
                                               write_corpus,
                                               write_sample,
)
from motionlang.datasets.synth.extract import extract, extract_keys, score
from motionlang.datasets.synth.spec import Primitive

__all__ = ["GENERATOR_VERSION", "Primitive", "SynthSample", "change_speed", "concat_samples",
           "extract", "extract_keys", "generate_sample", "ground_truth", "mirror_sample",
           "mirror_text", "score", "write_corpus", "write_sample"]

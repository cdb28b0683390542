"""Fuzzing the motion readers: mutated and crafted inputs (:mod:`.inputs`, built from the
byte-level edits of :mod:`.edits` and the HumanML3D-layout inputs of :mod:`.h3d_inputs`), the
seeds they start from (:mod:`.seeds`), and a child process that runs a reader on each under
memory and time limits and tells a clean error from a crash, a hang or an uncaught exception
(:mod:`.sandbox`). Used by ``tests/test_fuzz_readers.py`` and ``benchmarks/fuzz_readers.py``;
not part of the installed package: import it as ``fuzzing`` with ``benchmarks/`` on
``sys.path``.
"""
from .inputs import FORMATS, crafted, mutate
from .sandbox import Outcome, Sandbox
from .seeds import seeds

__all__ = ["FORMATS", "Outcome", "Sandbox", "crafted", "mutate", "seeds"]

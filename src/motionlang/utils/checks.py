"""One place for the range checks of config dataclasses (``__post_init__``).

Every model config checks its numbers where it is built, so a bad value is one
:class:`MotionlangError` naming the field, whether it came from the command line, the
Python API or a checkpoint, instead of a crash (or a silent model of NaNs) further on.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.utils import limits

#: numpy's legacy seeds are 32-bit: the range of every seed of the toolkit
SEED_MAX = 2**32 - 1
#: bounds that keep a mistyped size from allocating gigabytes: layer widths (an LSTM of
#: 4096 units holds 256 MB a matrix), stacked layers
MAX_SIZE = 4096
MAX_LAYERS = 16
#: hypotheses of one sentence (beam width, samples)
MAX_WIDTH = 1000
#: values per frame or per word a model reads (features, word or sentence vectors): the
#: richest layouts have a few thousand; a checkpoint asking for more is damaged or crafted
MAX_DIM = 100_000
#: special tokens a vocabulary holds besides its words (pad, sos, eos, unk)
VOCAB_SPECIALS = 4


def check_numbers(owner: str, cfg: Any, *, positive_ints: Iterable[str] = (),
                  nonneg_ints: Iterable[str] = (), positive: Iterable[str] = (),
                  nonneg: Iterable[str] = (), unit: Iterable[str] = (),
                  sizes: Iterable[str] = (), layers: Iterable[str] = (),
                  seeds: Iterable[str] = (), dims: Iterable[str] = (),
                  vocab: Iterable[str] = ()) -> None:
    """Raise if a field of ``cfg`` is out of range. ``positive_ints``: integers >= 1;
    ``nonneg_ints``: integers >= 0; ``positive``: finite numbers > 0; ``nonneg``: finite
    numbers >= 0; ``unit``: numbers in [0, 1); ``sizes``: integers in 1..:data:`MAX_SIZE`;
    ``layers``: integers in 1..:data:`MAX_LAYERS`; ``seeds``: integers in
    0..:data:`SEED_MAX`; ``dims``: integers in 1..:data:`MAX_DIM`; ``vocab``: vocabulary
    sizes, integers in 1..``max_vocabulary`` (:mod:`motionlang.utils.limits`) plus the
    :data:`VOCAB_SPECIALS`. A field set to None is not checked."""
    top_vocab = limits.current().max_vocabulary + VOCAB_SPECIALS if vocab else 0
    rules = [(sizes, lambda v: _is_int(v) and 1 <= v <= MAX_SIZE,
              f"an integer in 1..{MAX_SIZE}"),
             (dims, lambda v: _is_int(v) and 1 <= v <= MAX_DIM, f"an integer in 1..{MAX_DIM}"),
             (vocab, lambda v: _is_int(v) and 1 <= v <= top_vocab,
              f"an integer in 1..{top_vocab} (raise {limits.ENV['max_vocabulary']})"),
             (layers, lambda v: _is_int(v) and 1 <= v <= MAX_LAYERS,
              f"an integer in 1..{MAX_LAYERS}"),
             (seeds, lambda v: _is_int(v) and 0 <= v <= SEED_MAX,
              f"an integer in 0..{SEED_MAX}"),
             (positive_ints, lambda v: _is_int(v) and v >= 1, "an integer >= 1"),
             (nonneg_ints, lambda v: _is_int(v) and v >= 0, "an integer >= 0"),
             (positive, lambda v: _is_real(v) and v > 0, "a finite number > 0"),
             (nonneg, lambda v: _is_real(v) and v >= 0, "a finite number >= 0"),
             (unit, lambda v: _is_real(v) and 0 <= v < 1, "a number in [0, 1)")]
    for names, ok, what in rules:
        for name in names:
            v = getattr(cfg, name)
            if v is not None and not ok(v):
                odd = isinstance(v, float) and math.isfinite(v) and not real_ok(v)
                raise MotionlangError(f"{owner}.{name} must be {what}"
                                      f"{' (0 or 1e-12..1e12 in size)' if odd else ''}, "
                                      f"got {v!r}")


def check_bones(owner: str, bones: Any) -> list[float] | None:
    """A config's ``bones`` field (None, or 20 bone lengths in metres, 0 <= b < 10) as a
    list of floats; raise naming ``owner`` otherwise."""
    if bones is None:
        return None
    try:
        out = [float(b) for b in bones]
    except (TypeError, ValueError):
        out = []
    if len(out) != 20 or not all(0 <= b < 10 for b in out):
        raise MotionlangError(f"{owner}.bones: 20 lengths in metres, got {bones!r}")
    return out


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


#: the magnitudes of every real number the toolkit takes (0 aside): beyond them a rate, a
#: duration or a weight overflows a frame count, a GIF delay or a float32 tensor
MIN_MAGNITUDE, MAX_MAGNITUDE = 1e-12, 1e12


def real_ok(v: float) -> bool:
    """Whether ``v`` is finite and 0 or of a magnitude in 1e-12..1e12."""
    return math.isfinite(v) and (v == 0 or MIN_MAGNITUDE <= abs(v) <= MAX_MAGNITUDE)


def _is_real(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and real_ok(v)

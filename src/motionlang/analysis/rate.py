"""Does a file's frame rate look wrong? Some exports declare a rate their frames were never
captured at (MakeHuman's BVH of CMU trials: ``Frame Time 0.04``, 25 Hz, for 120 Hz takes),
and the take then plays several times too slowly: a walk is read as standing.

The evidence is the body's own: where the take at its declared rate shows no walking or
running, or steps slower than anyone walks (:data:`SLOWEST`), it is read again at the
capture rates of common systems (:data:`RATES`); if at one of them its legs step as people
walk or run through most of the take (:data:`COVER`; a cadence within :data:`CADENCE`,
slower than :data:`SLOWEST` at the declared rate; enough steps), the declared rate is suspect
and those rates are named (the steps cannot tell 100 Hz from 120 Hz: both are named).
Nothing is said where the take already steps as people do at its own rate, nor for files
that declare more than :data:`SUSPECT_BELOW` Hz (the misdeclared rates seen are video-like
ones).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from motionlang.analysis.analyse import analyse_positions
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import positions21
from motionlang.kinematics.motion import Motion

#: capture rates of common motion-capture systems (Hz), tried in turn
RATES = (60.0, 100.0, 120.0, 240.0)
#: steps a second of people walking or running (a slow walk to a fast run)
CADENCE = (1.4, 3.2)
#: steps a second below which no one walks (the slowest walks of the old are faster)
SLOWEST = 0.7
#: fewest steps that count as evidence
MIN_STEPS = 6
#: share of the take that must be walking or running at the other rate
COVER = 0.5
#: only files that declare at most this rate are checked (Hz)
SUSPECT_BELOW = 30.0
LOCOMOTION = ("walk", "run")


@dataclass(frozen=True)
class RateHint:
    """A declared rate that looks wrong: ``declared`` (Hz), the capture ``rates`` (Hz) at
    which the take steps as people do, with the ``cadences`` (steps a second) there, the
    ``steps`` seen and the cadence at the declared rate."""

    declared: float
    rates: tuple[float, ...]
    cadences: tuple[float, ...]
    steps: int
    declared_cadence: float

    def line(self, where: str) -> str:
        at = ", ".join(f"at {r:g} Hz {c:.1f}" for r, c in zip(self.rates, self.cadences))
        rate = f"{self.rates[0]:g}" if len(self.rates) == 1 else "RATE"
        which = "at that rate" if len(self.rates) == 1 else "at one of these rates"
        return (f"{where}: its header says {self.declared:g} Hz, but at that rate its "
                f"{self.steps} steps come {self.declared_cadence:.1f} a second, slower than "
                f"anyone walks ({at} a second): if it was captured {which}, pass "
                f"--source-fps {rate}")


def _steps(p21: np.ndarray, fps: float) -> tuple[int, float]:
    """(steps, seconds) of walking or running the analysis finds at ``fps``."""
    found = [f for f in analyse_positions(p21, fps).findings if f.label in LOCOMOTION]
    return sum(int(f.detail.get("steps") or 0) for f in found), \
        sum(f.end - f.start for f in found)


def rate_hint(p21: np.ndarray, fps: float) -> RateHint | None:
    """A :class:`RateHint` where the 21-joint positions ``p21`` (T, 21, 3) metres, declared
    at ``fps`` Hz, step like people only at other capture rates (module docstring); else
    None. Where several rates fit, all are named: the steps alone cannot tell them apart."""
    if not 0 < fps <= SUSPECT_BELOW or len(p21) < 2:
        return None
    steps, seconds = _steps(p21, fps)
    if steps >= MIN_STEPS and seconds > 0 and steps / seconds >= SLOWEST:
        return None   # it steps as people do at its own rate
    fits: list[tuple[float, float, int]] = []
    for rate in RATES:
        if rate <= fps * 1.5:
            continue
        n, seconds = _steps(p21, rate)
        if n < MIN_STEPS or seconds < COVER * len(p21) / rate:
            continue   # a few steps in a take that does something else: no evidence
        cadence = n / seconds
        # the same steps at the declared rate must be slower than anyone walks
        if CADENCE[0] <= cadence <= CADENCE[1] and cadence * fps / rate < SLOWEST:
            fits.append((rate, cadence, n))
    if not fits:
        return None
    rate, cadence, n = fits[0]
    return RateHint(fps, tuple(f[0] for f in fits), tuple(f[1] for f in fits), n,
                    cadence * fps / rate)


def warn_if_rate_looks_wrong(motion: Motion, where: str) -> None:
    """One warning (:meth:`RateHint.line`) where ``motion``'s rate looks wrong; nothing for
    a motion on a rig the body map cannot read (its command says so itself)."""
    if not 0 < motion.fps <= SUSPECT_BELOW:
        return
    try:
        p21 = positions21(motion)
    except MotionlangError:
        return
    hint = rate_hint(p21, motion.fps)
    if hint is not None:
        warnings.warn(hint.line(where), UserWarning, stacklevel=2)

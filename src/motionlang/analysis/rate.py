"""Does a file's frame rate look wrong? Some exports declare a rate their frames were never
captured at (MakeHuman's BVH of CMU trials: ``Frame Time 0.04``, 25 Hz, for 120 Hz takes),
and the take then plays several times too slowly: a walk is read as standing, a jump as
stepping up and down.

The evidence is the body's own, two clocks that are the same in every lab:

- **steps**: where the take at its declared rate shows no walking or running, or steps
  slower than anyone walks (:data:`SLOWEST`), it is read again at the capture rates of
  common systems (:data:`RATES`); if at one of them its legs step as people walk or run
  through most of the take (:data:`COVER`; a cadence within :data:`CADENCE`; enough steps),
  the declared rate is suspect. Steps cannot tell 100 Hz from 120 Hz: both are named, the
  one whose cadence lies nearer the middle of people's first.
- **gravity**: a body in flight (both feet off the floor) falls at g whatever the lab.
  The fitted fall of its centre of mass in flight (``features.body21.centre_of_mass21``;
  :data:`FLIGHT_FRAMES` or more frames each, parabolas that fit with their apex inside,
  the hands clear of the floor, no foot or hand held still while the body moves,
  :data:`FLIGHT_SECONDS` in all, flights that agree) gives the rate at which they fall at
  g; where that is well above the declared rate, the capture rates within
  :data:`FALL_TOLERANCE` of it are named, nearest first. A take that steps as people do at
  its declared rate is never named (a walk over a bridge rises and falls too).

Nothing is said where the take already steps or falls as people do at its own rate, nor for
files that declare more than :data:`SUSPECT_BELOW` Hz (the misdeclared rates seen are
video-like ones). Where the evidence names a rate, commands that read a file read it at that
rate and say so in one line (:func:`at_its_rate`); ``--source-fps`` chooses another.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from motionlang.analysis.body import CONTACT_HEIGHT, Body, J
from motionlang.analysis.evidence import runs
from motionlang.analysis.locomotion import G_LEGS, foot_passes, travel
from motionlang.errors import MotionlangError
from motionlang.features.body21 import centre_of_mass21
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
#: leg lengths one ankle leads the other by, along the way the body goes, in a step
PASS_LEAD = 0.1
#: share of the take that must be walking or running at the other rate
COVER = 0.5
#: only files that declare at most this rate are checked (Hz)
SUSPECT_BELOW = 30.0
#: fewest frames of one flight whose fall is fitted
FLIGHT_FRAMES = 8
#: seconds of flight in all (at the rate they give) that count as evidence
FLIGHT_SECONDS = 0.15
#: share of a flight's height variance its fitted parabola must explain
FLIGHT_FIT = 0.97
#: where in a flight (share of its span) the fitted fall's apex lies: a body thrown up
#: rises and falls; one rising onto something or sinking from it does not
APEX = (0.2, 0.8)
#: leg lengths above the floor both hands stay through a flight (a body on its hands is
#: held up, not falling)
HANDS_CLEAR = 0.3
#: a foot or hand moving at under this share of the centre of mass's speed is held still
HELD_SPEED = 0.2
#: share of a flight's moving frames in which one held still makes it no flight
HELD = 0.3
#: capture rates named from the flights lie within this share of the rate they give
FALL_TOLERANCE = 0.25
#: a declared rate is suspect where the evidence gives at least this many times it
SUSPECT_RATIO = 1.5
LOCOMOTION = ("walk", "run")
#: how a command-line user reads a file at another rate than the one named
CLI_ADVICE = "--source-fps HZ reads it at another rate"


@dataclass(frozen=True)
class RateHint:
    """A declared rate that looks wrong: ``declared`` (Hz) and the capture ``rates`` (Hz),
    likeliest first, at which the take steps (``cadences``, steps a second there, of
    ``steps`` seen; ``declared_cadence`` at the declared rate) or falls (``fall_rate``: the
    rate, Hz, at which its flights fall at g, of ``flights`` seen) as people do."""

    declared: float
    rates: tuple[float, ...]
    cadences: tuple[float, ...] = ()
    steps: int = 0
    declared_cadence: float = math.nan
    fall_rate: float | None = None
    flights: int = 0

    @property
    def rate(self) -> float:
        """The rate the take is read at (the likeliest)."""
        return self.rates[0]

    def evidence(self) -> str:
        """What the body showed, in words."""
        if self.cadences:
            at = ", ".join(f"at {r:g} Hz {c:.1f}" for r, c in zip(self.rates, self.cadences))
            return (f"its {self.steps} steps come {self.declared_cadence:.1f} a second, "
                    f"slower than anyone walks ({at} a second)")
        assert self.fall_rate is not None
        share = (self.declared / self.fall_rate) ** 2
        return (f"its {self.flights} flight(s) fall at {share:.2f} of gravity (at g at "
                f"{self.fall_rate:.0f} Hz)")

    def line(self, where: str, *, read: bool = False, advice: str | None = CLI_ADVICE) -> str:
        """The warning; ``read``: the take is read at :attr:`rate` (said so), with
        ``advice`` on reading it otherwise (the command line's; None: none, a page has no
        flags)."""
        said = f"{where}: its header says {self.declared:g} Hz, but at that rate " \
               f"{self.evidence()}"
        if read:
            return f"{said}: read at {self.rate:g} Hz" + (f" ({advice})" if advice else "")
        rate = f"{self.rates[0]:g}" if len(self.rates) == 1 else "RATE"
        which = "at that rate" if len(self.rates) == 1 else "at one of these rates"
        return f"{said}: if it was captured {which}, pass --source-fps {rate}"


def _steps(p21: np.ndarray, fps: float, *, passes: bool = False) -> tuple[int, float]:
    """(steps, seconds) of walking or running the analysis finds at ``fps``: its feet's
    contacts, or with ``passes`` one more than the times one foot passes the other along
    the way the body goes (:func:`_passes`), which no rate changes. A take read slower
    than it was captured drags its feet, and each drag splits a contact: its own rate is
    judged by the passes."""
    body = Body.from_positions(p21, fps)
    found = [f for f in travel(body) if f.label in LOCOMOTION]
    seconds = sum(f.end - f.start for f in found)
    if not passes:
        return sum(int(f.detail.get("steps") or 0) for f in found), seconds
    counts = [_passes(body, int(round(f.start * body.fps)), int(round(f.end * body.fps)))
              for f in found]
    return sum(n + 1 for n in counts if n), seconds


def _passes(body: Body, a: int, b: int) -> int:
    """How often, in frames ``a:b``, the leading foot along the direction of travel
    changes: the ankles' horizontal lead crossing :data:`PASS_LEAD` leg lengths one way,
    then the other."""
    v = body.ground_velocity[a:b]
    way = v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-9)
    ankles = body.p[a:b][:, [J["LA"], J["RA"]]][:, :, [0, 2]]
    lead = ((ankles[:, 0] - ankles[:, 1]) * way).sum(axis=1) / body.leg
    return foot_passes(lead, PASS_LEAD)


def fall_rate(p21: np.ndarray, fps: float) -> tuple[float, int, float] | None:
    """``(rate Hz, flights, seconds)``: the rate at which the flights of ``p21`` (T, 21, 3),
    declared at ``fps``, fall at g (their frames' fitted fall, median over their frames), how
    many were fitted and their seconds at that rate; None where no flight can be fitted or
    the flights disagree by more than :data:`FALL_TOLERANCE`.
    Gravity in leg lengths assumes an adult's leg (``locomotion.G_LEGS``); a child's shorter
    leg reads the rate a few per cent high."""
    body = Body.from_positions(p21, fps)
    step = fps / body.fps   # frames of p21 in one of the body's
    # the take's own floor, not the analysis' local one: that follows the feet over a
    # window of seconds, and a flight at the wrong rate lasts several
    lowest = body.foot_low.min(axis=0)
    floor = float(np.percentile(lowest, 5))
    falls, weights = [], []
    for a, b in runs(lowest - floor > CONTACT_HEIGHT * body.leg):
        if a == 0 or b >= body.n or (b - a) * step < FLIGHT_FRAMES or b - a < 4:
            continue   # a flight cut by the take's ends has no take-off or landing
        if body.p[a:b, [J["LW"], J["RW"]], 1].min() - floor < HANDS_CLEAR * body.leg:
            continue   # on the hands (a cartwheel, a handstand): held up, not falling
        if _held(body.p[a:b]):
            continue   # a foot or a hand held still on something (a bridge, a bar)
        y = centre_of_mass21(body.p[a:b])[:, 1] / body.leg
        k = np.arange(b - a, dtype=float)
        coef = np.polyfit(k, y, 2)
        spread = float(np.var(y))
        if coef[0] >= 0 or spread <= 0 or \
                not APEX[0] < -coef[1] / (2 * coef[0]) / (b - a - 1) < APEX[1]:
            continue   # it does not rise and fall: held up, on a step, on a seat
        fit = 1.0 - float(np.mean((np.polyval(coef, k) - y) ** 2)) / spread
        if fit < FLIGHT_FIT:
            continue
        falls.append(-2.0 * float(coef[0]))   # leg lengths per body frame squared
        weights.append(b - a)
    if not falls:
        return None
    order = np.argsort(falls)
    cum = np.cumsum(np.asarray(weights)[order])
    fall = falls[int(order[np.searchsorted(cum, cum[-1] / 2.0)])]
    if any(abs(math.sqrt(fall / f) - 1.0) > FALL_TOLERANCE for f in falls):
        return None   # flights that disagree: not all of them were flights
    rate = math.sqrt(G_LEGS / fall) * step   # body frames a second at g, in p21's frames
    return rate, len(falls), float(sum(weights)) * step / rate


def _held(p: np.ndarray) -> bool:
    """Whether, over a span (T, 21, 3) with the feet off the floor, a foot or a hand stays
    still in the world while the centre of mass moves (:data:`HELD`): the body stands or
    hangs on something (a raised floor, a bar), it does not fly. In flight nothing is
    still: the limbs go with the body."""
    com = np.linalg.norm(np.diff(centre_of_mass21(p), axis=0), axis=-1)
    moving = com > np.median(com)   # the apex, where the body is still, says nothing
    if moving.sum() < 2:
        return False
    for j in ("LF", "RF", "LW", "RW"):
        speed = np.linalg.norm(np.diff(p[:, J[j]], axis=0), axis=-1)
        if np.mean(speed[moving] < HELD_SPEED * com[moving]) >= HELD:
            return True
    return False


def rate_hint(p21: np.ndarray, fps: float) -> RateHint | None:
    """A :class:`RateHint` where the 21-joint positions ``p21`` (T, 21, 3) metres, declared
    at ``fps`` Hz, step or fall like people only at other capture rates (module
    docstring); else None."""
    return rate_verdict(p21, fps).hint


@dataclass(frozen=True)
class RateVerdict:
    """What a body says of its declared rate: a :class:`RateHint` where it looks wrong;
    ``own`` where the body confirms it (it steps as people do, or its flights fall at g, at
    that rate); neither where nothing in it can tell. ``read``: whether a body of two or
    more frames was read at all (not: a rig no map fits, one frame, a rate above
    :data:`SUSPECT_BELOW`)."""

    hint: RateHint | None = None
    own: bool = False
    read: bool = True


def rate_verdict(p21: np.ndarray, fps: float) -> RateVerdict:
    """:func:`rate_hint`, and whether the body confirms its declared rate instead."""
    if not 0 < fps <= SUSPECT_BELOW or len(p21) < 2:
        return RateVerdict(read=False)
    try:
        steps, seconds = _steps(p21, fps, passes=True)
        if steps >= MIN_STEPS and seconds > 0 and steps / seconds >= SLOWEST:
            return RateVerdict(own=True)   # it steps as people do at its own rate
        # gravity next: it gives the rate itself, steps only a range of rates
        fall = fall_rate(p21, fps)
        if fall is not None and abs(fall[0] / fps - 1.0) <= FALL_TOLERANCE and \
                fall[2] >= FLIGHT_SECONDS:
            return RateVerdict(own=True)   # its flights fall at g at its own rate
        return RateVerdict(_by_flights(p21, fps, fall) or _by_steps(p21, fps))
    except MotionlangError:   # no body to read: nothing to say about its rate
        return RateVerdict(read=False)


def _by_steps(p21: np.ndarray, fps: float) -> RateHint | None:
    fits: list[tuple[float, float, int]] = []
    for rate in RATES:
        if rate <= fps * SUSPECT_RATIO:
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
    middle = math.sqrt(CADENCE[0] * CADENCE[1])
    fits.sort(key=lambda f: abs(math.log(f[1] / middle)))
    rate, cadence, n = fits[0]
    return RateHint(fps, tuple(f[0] for f in fits), tuple(f[1] for f in fits), n,
                    cadence * fps / rate)


def _by_flights(p21: np.ndarray, fps: float,
                fall: tuple[float, int, float] | None) -> RateHint | None:
    if fall is None:
        return None
    rate, flights, seconds = fall
    if rate < fps * SUSPECT_RATIO or seconds < FLIGHT_SECONDS:
        return None   # it falls as bodies do at its own rate, or too little to tell
    near = sorted((r for r in RATES if abs(r / rate - 1.0) <= FALL_TOLERANCE),
                  key=lambda r: abs(math.log(r / rate)))
    if not near:
        return None
    return RateHint(fps, tuple(near), fall_rate=rate, flights=flights)


def hint_of(motion: Motion) -> RateHint | None:
    """:func:`rate_hint` of a motion of any rig (None for a rig the body map cannot read:
    its command says so itself)."""
    return verdict_of(motion).hint


def verdict_of(motion: Motion) -> RateVerdict:
    """:func:`rate_verdict` of a motion of any rig (nothing said for a rig the body map
    cannot read)."""
    if not 0 < motion.fps <= SUSPECT_BELOW:
        return RateVerdict(read=False)
    try:
        p21 = positions21(motion)
    except MotionlangError:
        return RateVerdict(read=False)
    return rate_verdict(p21, motion.fps)


def at_its_rate(motion: Motion, where: str, *, advice: str | None = CLI_ADVICE) -> Motion:
    """``motion`` at the rate its body's steps or flights say it was captured at, with one
    warning that says so (and ``advice`` on reading it at another, :meth:`RateHint.line`),
    where its declared rate looks wrong (:class:`RateHint`); the motion as it is elsewhere.
    The declared rate is kept in ``meta["declared_fps"]``."""
    hint = hint_of(motion)
    if hint is None:
        return motion
    return read_at(motion, hint.rate, hint.line(where, read=True, advice=advice))


def read_at(motion: Motion, rate: float, line: str) -> Motion:
    """``motion`` at ``rate`` Hz, its declared rate kept in ``meta["declared_fps"]``, with
    the warning ``line`` (what the body showed)."""
    warnings.warn(line, UserWarning, stacklevel=3)
    return motion.replace(fps=rate, meta={**motion.meta, "declared_fps": motion.fps})


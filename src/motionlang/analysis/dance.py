"""Dancing: seconds on end in which the body keeps moving and does many different things,
something of the legs and something of the arms among them.

No single movement makes a dance: a ballet dancer's battement is a fast, high swing of a
straight leg, as a kick is, and a pirouette is a spin. What tells the dance is the mix. A
stretch dances where, within every :data:`WINDOW` seconds of it,

- the limbs keep moving: a wrist or an ankle moves faster than :data:`LIMB_MOVING` leg
  lengths a second, relative to the pelvis, in at least :data:`ACTIVE` of the frames (a pose
  held for a photograph, or a balance held still, is not a dance);
- the other detectors found at least :data:`KINDS` different movements, at least one of the
  legs (:data:`LEG_MOVES`: a kick or a leg swung high, a spin, a balance on one leg) and one of
  the arms (:data:`ARM_MOVES`); a spin during a kick is the kick's own turn (a spinning
  kick), not a movement of its own;
- nothing strikes (:data:`STRIKES`): kicks and punches together are fighting, said as such.

and the stretch lasts at least :data:`MIN_DANCE` seconds. The movements it is made of are
kept in the finding's detail (``moves``), so that a sentence can say what the dance shows.
"""
from __future__ import annotations

import numpy as np

from motionlang.analysis.body import ARMS, LEGS, Body
from motionlang.analysis.evidence import MIN_CONFIDENCE, Finding, confidence, overlap, runs

WINDOW = 4.0          # s
STEP = 0.5            # s between the windows' starts
MIN_DANCE = 3.0       # s
KINDS = 3             # different movements within a window
ACTIVE = 0.5          # share of a window's frames with a limb end moving
LIMB_MOVING = 1.0     # L/s: a wrist or ankle relative to the pelvis
LEG_MOVES = ("kick", "spin", "one_leg")
ARM_MOVES = ("raise", "wave", "arms_out", "clap")
OTHER_MOVES = ("jump", "hop", "bow")
STRIKES = ("punch",)
MOVES = frozenset(LEG_MOVES + ARM_MOVES + OTHER_MOVES)
#: findings a dance says (most of their span inside it): the movements it is made of and
#: the steps and turns between them
WITHIN = LEG_MOVES + ARM_MOVES + OTHER_MOVES + ("turn", "walk", "reach", "bend", "stand")


def limbs_moving(body: Body) -> np.ndarray:
    """(T,) bool: a wrist or an ankle moves faster than :data:`LIMB_MOVING` relative to
    the pelvis (the limbs at work, whatever the body's travel)."""
    pelvis = body.p[:, 0]
    ends = [w for _, _, w in ARMS] + [a for _, _, a in LEGS]
    speed = np.stack([body.speed_of(body.p[:, e] - pelvis) for e in ends]) / body.leg
    return speed.max(axis=0) > LIMB_MOVING


def _moves(found: list[Finding], t0: float, t1: float) -> set[str]:
    """The labels of the movements within [t0, t1), a spin during a kick not counted
    (wherever the kick lies: a spinning kick cut by the window's edge is still one)."""
    inside = [f for f in found if f.end > t0 and f.start < t1]
    kicks = [f for f in found if f.label == "kick"]
    return {f.label for f in inside
            if not (f.label == "spin" and any(overlap(f, k) > 0.5 * k.duration for k in kicks))}


def dances(body: Body, found: list[Finding]) -> list[Finding]:
    """The stretches of ``body`` that dance (module docstring), given the other detectors'
    ``found`` findings on it (pruned: one finding per thing the body does)."""
    if body.duration < MIN_DANCE:
        return []
    moving = limbs_moving(body)
    dancing = np.zeros(body.n, dtype=bool)
    kinds = np.zeros(body.n)
    # windows counted in frames, so that a header's absurd frame rate cannot make them many
    width = max(1, round(WINDOW * body.fps))
    for i0 in range(0, body.n, max(1, round(STEP * body.fps))):
        i1 = min(body.n, i0 + width)
        labels = _moves(found, i0 / body.fps, i1 / body.fps)
        n = len(labels & MOVES)
        if n >= KINDS and labels & set(LEG_MOVES) and labels & set(ARM_MOVES) and \
                not labels & set(STRIKES) and moving[i0:i1].mean() >= ACTIVE:
            dancing[i0:i1] = True
            kinds[i0:i1] = np.maximum(kinds[i0:i1], n)
        if i1 == body.n:
            break
    out = []
    for a, b in runs(dancing):
        start, end = body.t(a), body.t(b)
        if end - start < MIN_DANCE:
            continue
        peak = float(kinds[a:b].max())
        # counts are whole: the threshold lies half-way below the least that passes
        c = confidence(peak, KINDS - 0.5, 1.0)
        moves = sorted(_moves(found, start, end) & MOVES)
        if c >= MIN_CONFIDENCE:
            out.append(Finding("limb", "dance", start, end,
                               f"different movements within {WINDOW:g} s", peak,
                               KINDS - 0.5, c, detail={"moves": moves}))
    return out


def said_by_dance(found: list[Finding]) -> list[Finding]:
    """``found`` without the findings a dance among them says (:data:`WITHIN`, at least
    half of their span inside it)."""
    danced = [f for f in found if f.label == "dance"]
    if not danced:
        return found
    return [f for f in found if not (f.label in WITHIN and any(
        overlap(f, d) >= 0.5 * max(f.duration, 1e-6) for d in danced))]

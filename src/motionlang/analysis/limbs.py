"""What the arms, legs and trunk do, as events with their repetitions counted.

- **raises** an arm: the wrist lifted to the shoulder's height or above (:data:`RAISE`),
  held;
- **waves**: a raised hand swinging from side to side (:data:`WAVE_SWINGS` swings or more);
- **punches**: a fast straightening of the arm away from the shoulder, at chest height, the
  fist driven along the line of the arm (:data:`PUNCH_LINE`) and drawn back
  (:data:`PUNCH_HOLD`);
- **kicks**: a fast, high swing of a nearly straight leg;
- **reaches**: an arm held straight out in front;
- **bends over**: the trunk tilted far forward on straight legs;
- **bows**: the trunk leaning forward from upright and back again, standing still;
- **touches the floor**: a hand at the floor while the body is not on all fours or lying;
- **claps**: both hands meeting fast, again and again.

Speeds are in limb lengths a second and heights in leg or arm lengths, so that a child's
punch and an adult's compare alike.
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter1d

from motionlang.analysis.body import ARMS, LEGS, SIDES, Body, J
from motionlang.analysis.evidence import (
    MIN_CONFIDENCE,
    Finding,
    clean_mask,
    confidence,
    merge_series,
    runs,
)
from motionlang.analysis.posture import (
    HAND_NEAR_FLOOR,
    all_fours,
    height_over_floor,
    knee_flexion,
    lying,
)

RAISE = -0.05              # arm lengths: wrist over shoulder (a hanging arm is near -1; a
                           # raise lifts the hand to the shoulder or above)
MIN_RAISE = 0.4            # s
WAVE_LEVEL = -0.1          # arm lengths: the waving wrist at least this high over the shoulder
WAVE_AMPLITUDE = 0.06      # L: half the side-to-side swing
WAVE_SWINGS = 3            # direction changes
WAVE_RATE = (0.6, 5.0)     # swings a second... per half-cycle, Hz
PUNCH_FROM, PUNCH_TO = 0.7, 0.9   # share of the arm's length, bent -> straight
PUNCH_TIME = 0.35          # s: the straightening takes at most this
PUNCH_SPEED = 2.5          # arm lengths a second of extension at its peak
PUNCH_LEVEL = 0.35         # arm lengths: the fist at most this far below the shoulder
PUNCH_OUT = 0.55           # arm lengths: the fist this far out horizontally
PUNCH_LINE = 0.7           # share of the fist's speed (from the shoulder) along the arm when
                           # it straightens fastest: a punch drives the fist out along the
                           # arm, a sweep (a dancer's port de bras, a wave) carries it round
PUNCH_HOLD = 1.2           # s: a punch is withdrawn; an arm that stays straight out longer
                           # pushed, reached or followed a shot or throw through
KICK_HELD = 0.8            # s: a leg held high longer than this is a pose, not a kick
KICK_HEIGHT = 0.3          # L: ankle over the floor
KICK_AWAY = 0.45           # L: ankle away from the hip, horizontally
KICK_TRAVEL = 1.5          # L/s: the body moves slower than this while it kicks
KICK_SPEED = 3.0           # L/s: the foot's peak speed
KICK_KNEE = 75.0           # deg: the knee at most this bent at some moment of the kick
KICK_TILT = 100.0          # deg: a high kick leans the trunk back, but the body is not upside down
REACH_FORWARD = 0.6        # arm lengths: wrist ahead of the shoulder
BEND_TILT = 50.0           # deg
BOW_TILT = 25.0            # deg: a bow leans the trunk forward at least this far...
BOW_LONGEST = 4.0          # s: ...and comes back upright within this
BEND_PELVIS = 0.75         # standing pelvis heights: legs still mostly straight
CLAP_CLOSE = 0.15          # L: wrists this close
CLAP_SPEED = 1.5           # L/s: closing speed before the contact
EVENT_GAP = 0.25           # s


def _rel_wrist(body: Body, side: int) -> np.ndarray:
    """(T, 3) wrist minus shoulder in the body frame (x left, y up, z forward), metres."""
    s, _, w = ARMS[side]
    return body.to_body_frame(body.p[:, w] - body.p[:, s])


def raises(body: Body) -> list[Finding]:
    out: list[Finding] = []
    masks = []
    upright = ~lying(body)   # lying, a hand at the shoulder's height is lying too
    for side in range(2):
        arm = body.arm_length(side)
        up = _rel_wrist(body, side)[:, 1] / arm
        masks.append((clean_mask((up > RAISE) & upright, body.fps, min_len=MIN_RAISE,
                                 max_gap=EVENT_GAP), up))
    both = masks[0][0] & masks[1][0]
    for a, b in runs(clean_mask(both, body.fps, min_len=MIN_RAISE, max_gap=EVENT_GAP)):
        v = float(np.median(np.minimum(masks[0][1][a:b], masks[1][1][a:b])))
        out.append(Finding("limb", "raise", body.t(a), body.t(b), "wrist over shoulder "
                           "(arm lengths)", v, RAISE, confidence(v, RAISE, 0.3,
                           duration=(b - a) / body.fps, full_after=0.6), side="both"))
    for side in range(2):
        only = masks[side][0] & ~both
        for a, b in runs(clean_mask(only, body.fps, min_len=MIN_RAISE, max_gap=EVENT_GAP)):
            v = float(np.median(masks[side][1][a:b]))
            out.append(Finding("limb", "raise", body.t(a), body.t(b), "wrist over shoulder "
                               "(arm lengths)", v, RAISE, confidence(
                                   v, RAISE, 0.3, duration=(b - a) / body.fps,
                                   full_after=0.6), side=SIDES[side]))
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]


def _swings(x: np.ndarray, amplitude: float) -> list[int]:
    """Indices where a 1-D signal turns back after moving at least ``amplitude`` * 2."""
    turns: list[int] = []
    last = 0
    direction = 0
    ext = x[0]
    for i in range(1, len(x)):
        if direction >= 0 and x[i] > ext:
            ext, last = x[i], i
            direction = 1 if direction == 0 and x[i] - x[0] > amplitude else direction
        elif direction <= 0 and x[i] < ext:
            ext, last = x[i], i
            direction = -1 if direction == 0 and x[0] - x[i] > amplitude else direction
        if direction == 1 and ext - x[i] > 2 * amplitude:
            turns.append(last)
            direction, ext, last = -1, x[i], i
        elif direction == -1 and x[i] - ext > 2 * amplitude:
            turns.append(last)
            direction, ext, last = 1, x[i], i
    return turns


def waves(body: Body) -> list[Finding]:
    out: list[Finding] = []
    per_side = []
    for side in range(2):
        arm = body.arm_length(side)
        rel = _rel_wrist(body, side)
        high = clean_mask(rel[:, 1] / arm > WAVE_LEVEL, body.fps, min_len=0.8, max_gap=EVENT_GAP)
        spans = []
        for a, b in runs(high):
            x = rel[a:b, 0] / body.leg
            x = x - uniform_filter1d(x, max(3, body.frames(1.0)) | 1, mode="nearest")
            t = _swings(x, WAVE_AMPLITUDE)
            if len(t) < WAVE_SWINGS:
                continue
            rate = (len(t) - 1) / max((t[-1] - t[0]) / body.fps, 1e-6) / 2
            if not WAVE_RATE[0] <= rate <= WAVE_RATE[1]:
                continue
            # the wave is the whole time the hand is up: raising it is part of waving
            spans.append((a, b, len(t)))
        per_side.append(spans)
    for side in range(2):
        for a, b, n in per_side[side]:
            partner = [s for s in per_side[1 - side] if min(b, s[1]) - max(a, s[0]) > 0]
            if partner and side == 1:
                continue    # counted once, as both, from the left side
            who = "both" if partner else SIDES[side]
            out.append(Finding("limb", "wave", body.t(a), body.t(b), "side-to-side swings",
                               float(n), WAVE_SWINGS, confidence(n, WAVE_SWINGS, 3),
                               side=who, count=max(1, (n + 1) // 2)))  # a wave: there and back
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]


def punches(body: Body) -> list[Finding]:
    out: list[Finding] = []
    for side in range(2):
        s, _, w = ARMS[side]
        arm = body.arm_length(side)
        arm_vec = body.p[:, w] - body.p[:, s]
        d = np.linalg.norm(arm_vec, axis=1) / arm
        rel = _rel_wrist(body, side)
        rate = np.gradient(d) * body.fps
        fist = np.linalg.norm(np.gradient(arm_vec, axis=0), axis=1) * body.fps / arm
        along = rate / np.maximum(fist, 1e-9)   # the straightening's share of the fist's speed
        # at chest to head height and straight out, not down (a dribble) or up (a raise)
        height_ok = (body.p[:, w, 1] > body.p[:, s, 1] - PUNCH_LEVEL * arm) & \
            (body.p[:, w, 1] < body.p[:, J["BUN"], 1] + 0.2 * body.leg) & \
            (np.abs(rel[:, 1]) < 0.6 * np.linalg.norm(rel, axis=1))
        events = []
        window = body.frames(PUNCH_TIME)
        i = 0
        while i < body.n:
            # out from the shoulder to the front or the side (the trunk turns with a
            # punch, so "in front" is not asked of the facing), never behind
            out_ok = np.hypot(rel[i, 0], rel[i, 2]) > PUNCH_OUT * arm and rel[i, 2] > -0.1 * arm
            if d[i] >= PUNCH_TO and height_ok[i] and out_ok:
                lo = max(0, i - window)
                if d[lo:i + 1].min() <= PUNCH_FROM:
                    top = lo + int(np.argmax(rate[lo:i + 1]))
                    peak = float(rate[top])
                    if peak >= PUNCH_SPEED and along[top] >= PUNCH_LINE:
                        start = i
                        # wait for the arm to bend again before the next punch
                        while i < body.n and d[i] > PUNCH_FROM + 0.1:
                            i += 1
                        if i - start <= body.frames(PUNCH_HOLD):   # (or the take ends)
                            events.append((int(lo + np.argmin(d[lo:start + 1])), start + 1,
                                           peak))
                        continue
            i += 1
        if events:
            out.extend(_series(body, "punch", events, SIDES[side], "arm extension speed "
                               "(arm lengths/s)", PUNCH_SPEED, 2.0))
    return out


def kicks(body: Body) -> list[Finding]:
    out: list[Finding] = []
    flex = knee_flexion(body)
    for side in range(2):
        h, _, a = LEGS[side]
        height = height_over_floor(body, a)
        speed = body.speed_of(body.p[:, a]) / body.leg
        ahead = np.linalg.norm((body.p[:, a] - body.p[:, h])[:, [0, 2]], axis=1) / body.leg
        standing_on = body.contacts[1 - side]
        # the foot up and away from the hip; the knee straightens at some moment of it (a
        # kick chambers bent and extends) and the body is not upside down (a cartwheel)
        cand = (height > KICK_HEIGHT) & (ahead > KICK_AWAY) & (body.trunk_tilt < KICK_TILT)
        events = []
        for lo, hi in runs(cand):
            w = body.frames(0.3)
            peak = float(speed[max(0, lo - w):hi].max())
            support = float(standing_on[max(0, lo - w):hi].mean())
            straight = float(flex[side, lo:hi].min()) < KICK_KNEE
            # a running stride throws the foot high too: a kick is made from a stance
            slow = float(np.median(body.ground_speed[lo:hi])) < KICK_TRAVEL
            if peak >= KICK_SPEED and (hi - lo) / body.fps <= KICK_HELD and support > 0.5 \
                    and straight and slow:
                events.append((lo, hi, peak))
        if events:
            out.extend(_series(body, "kick", events, SIDES[side], "foot speed (L/s)",
                               KICK_SPEED, 2.0))
    return out


def _series(body: Body, label: str, events: list[tuple[int, int, float]], side: str,
            measure: str, threshold: float, scale: float) -> list[Finding]:
    """Events of one side within 1.5 s of each other as one finding with a count."""
    groups: list[list[tuple[int, int, float]]] = []
    for e in events:
        if groups and e[0] - groups[-1][-1][1] < body.frames(1.5):
            groups[-1].append(e)
        else:
            groups.append([e])
    out = []
    for g in groups:
        peak = float(np.median([e[2] for e in g]))
        c = confidence(peak, threshold, scale)
        if c >= MIN_CONFIDENCE:
            out.append(Finding("limb", label, body.t(g[0][0]), body.t(g[-1][1]), measure, peak,
                               threshold, c, side=side, count=len(g),
                               detail={"times": [round(body.t(e[0]), 2) for e in g]}))
    return out


def reaches(body: Body) -> list[Finding]:
    out: list[Finding] = []
    for side in range(2):
        arm = body.arm_length(side)
        rel = _rel_wrist(body, side) / arm
        m = clean_mask((rel[:, 2] > REACH_FORWARD) & (rel[:, 1] > -0.3) & (rel[:, 1] < 0.45),
                       body.fps, min_len=0.5, max_gap=EVENT_GAP)
        for a, b in runs(m):
            v = float(np.median(rel[a:b, 2]))
            out.append(Finding("limb", "reach", body.t(a), body.t(b), "wrist ahead of the "
                               "shoulder (arm lengths)", v, REACH_FORWARD,
                               confidence(v, REACH_FORWARD, 0.2), side=SIDES[side]))
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]


def bends(body: Body) -> list[Finding]:
    m = clean_mask((body.trunk_tilt > BEND_TILT) & (body.pelvis_height > BEND_PELVIS) &
                   _leans_forward(body) & ~lying(body), body.fps, min_len=0.4,
                   max_gap=EVENT_GAP)
    out = []
    for a, b in runs(m):
        v = float(np.median(body.trunk_tilt[a:b]))
        out.append(Finding("limb", "bend", body.t(a), body.t(b), "trunk tilt from vertical "
                           "(deg)", v, BEND_TILT, confidence(v, BEND_TILT, 20.0)))
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]


def _leans_forward(body: Body) -> np.ndarray:
    """(T,) bool: the neck ahead of the pelvis along the facing (not leaning back)."""
    lean = (body.p[:, J["BLN"]] - body.p[:, 0])[:, [0, 2]]
    return (lean * body.forward).sum(axis=1) > 0


def bows(body: Body) -> list[Finding]:
    m = clean_mask((body.trunk_tilt > BOW_TILT) & (body.pelvis_height > BEND_PELVIS) &
                   _leans_forward(body) & (body.ground_speed < 0.5), body.fps, min_len=0.3,
                   max_gap=EVENT_GAP)
    out = []
    for a, b in runs(m):
        if (b - a) / body.fps > BOW_LONGEST or a == 0 or b >= body.n:
            continue    # held, or not begun and ended upright within the take
        v = float(body.trunk_tilt[a:b].max())
        out.append(Finding("limb", "bow", body.t(a), body.t(b), "trunk tilt from vertical "
                           "(deg)", v, BOW_TILT, confidence(v, BOW_TILT, 10.0)))
    return merge_series([f for f in out if f.confidence >= MIN_CONFIDENCE])


def touches_floor(body: Body) -> list[Finding]:
    hands = np.stack([height_over_floor(body, w) for _, _, w in ARMS])
    low = hands.min(axis=0)
    m = clean_mask((low < HAND_NEAR_FLOOR) & ~lying(body) & ~all_fours(body), body.fps,
                   min_len=0.15, max_gap=EVENT_GAP)
    out = []
    for a, b in runs(m):
        v = float(low[a:b].min())
        side = "left" if hands[0, a:b].min() < hands[1, a:b].min() else "right"
        out.append(Finding("limb", "touch_floor", body.t(a), body.t(b), "hand over the floor "
                           "(L)", v, HAND_NEAR_FLOOR, confidence(v, HAND_NEAR_FLOOR, -0.15),
                           side=side))
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]


def claps(body: Body) -> list[Finding]:
    d = np.linalg.norm(body.p[:, J["LW"]] - body.p[:, J["RW"]], axis=1) / body.leg
    closing = -np.gradient(d) * body.fps
    events = []
    for a, b in runs(d < CLAP_CLOSE):
        w = body.frames(0.2)
        peak = float(closing[max(0, a - w):a + 1].max())
        if peak >= CLAP_SPEED:
            events.append((a, b, peak))
    if len(events) < 2:
        return []
    return [f for f in _series(body, "clap", events, "both", "hands closing speed (L/s)",
                               CLAP_SPEED, 1.0) if f.count >= 2]


def limb_actions(body: Body) -> list[Finding]:
    """Every limb event of the take (module docstring)."""
    found: list[Finding] = []
    for detector in (raises, waves, punches, kicks, reaches, bends, bows, touches_floor,
                     claps):
        found.extend(detector(body))
    return sorted(found, key=lambda f: f.start)

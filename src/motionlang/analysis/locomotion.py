"""Locomotion, turns and changes of level: where the body goes and how.

- **Travel** is a span in which the root moves faster than :data:`TRAVEL` leg lengths a
  second for at least :data:`MIN_TRAVEL` s. Its gait comes from the feet
  (``features.gait``: a walk always has a foot down and double support, a run has flights;
  the Froude number decides where the feet are unclear), its speed word from the Froude
  number ``v^2 / (g L)`` (people walk near 0.15-0.25 and change to running near 0.5;
  Alexander 1989), its direction from the angle between travel and facing (forward,
  backwards, sideways left or right), and its path from how much the direction of travel
  turns (straight, curving left or right, a circle).
- **In place**: where the root stays but the feet swing past each other by a stride
  (:func:`striding`: a treadmill, or a take whose root's travel was taken out), the body
  walks in place, or runs where its lower foot leaves the floor and its cadence is a
  runner's; each pass of one foot by the other is a step.
- **Jumps** are flights from both feet (or long flights from one), forward, up or down by
  where they land; a flight is one only where the body falls as thrown bodies fall (its
  mean point's fitted vertical acceleration near gravity's, :func:`ballistic`), which a
  body up on its toes or held by a bar or a climbing frame does not; **hops** are repeated
  flights from one and the same foot.
- **Turns** are changes of facing of at least :data:`MIN_TURN` degrees within a few seconds,
  their angle rounded to 45 degrees; :data:`SPIN_TURN` degrees or more fast is a spin.
- **Level changes**: the height of the supporting feet moves up or down by a step or more
  (steps or climbs up, steps, climbs or jumps down).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.ndimage import maximum_filter1d, median_filter, minimum_filter1d, uniform_filter1d

from motionlang.analysis.body import Body
from motionlang.analysis.evidence import MIN_CONFIDENCE, Finding, clean_mask, confidence, runs
from motionlang.features.gait import GRAVITY, gait

TRAVEL = 0.25              # L/s: slower than this the root is not travelling
MIN_TRAVEL = 0.8           # s
STRIDE_SWING = 1.0         # L: feet that change places fore and aft by this...
STRIDE_WINDOW = 2.0        # s: ...within this are striding (a walking stride is ~1.5 L)
IN_PLACE_MIN = 2.0         # s: striding in place at least this long is a walk in place
STEP_LIFT = 0.03           # L: each foot raised this far above the other within a stride
                           # window is stepping (in place, sideways or back), not standing
PASS_MARGIN = 0.25         # L: in place, a foot passes the other once this far ahead of it
# in place the root's speed says nothing of the gait: a run has flights (the lower foot
# leaves the floor) and a quick cadence; walks stay below both
IN_PLACE_FLIGHT = 0.025    # L: the lower foot's 90th minus 10th height percentile, at least
IN_PLACE_CADENCE = 1.9     # steps a second, at least
MIN_DISTANCE = 0.5         # L: a travel covers at least this...
MIN_LIFTS = 2              # ...and the feet leave the floor and land again this often
FOOT_BORNE = 0.25          # share of its frames a walk or run has a foot on the floor at least
UPRIGHT = 45.0             # deg: a walk's or run's trunk is at most this far from vertical
UPRIGHT_PELVIS = 0.6       # standing pelvis heights: and its pelvis at least this high
CURVE_DISTANCE = 2.0       # L: a path shorter than this is too short to curve
SIDEWAYS = 50.0            # deg between travel and facing beyond which it is sideways
BACKWARDS = 130.0          # deg beyond which it is backwards
CURVE = 45.0               # deg of turning of the path that make it curve
CIRCLE = 300.0             # deg that make it a circle
# Froude numbers of the speed words: walking and running each have a slow and a fast end
WALK_SLOW, WALK_BRISK = 0.08, 0.3
JOG_UPTO, SPRINT_FROM = 1.0, 2.5
WALK_LIMIT = 1.0           # Froude number above which no gait is a walk
GAIT_WINDOW = 2.0          # s: the windows a long travel's gait is read in
GAIT_HOLD = 1.5            # s: a change of gait that lasts less is not one
JUMP_FLIGHT = 0.12         # s: shortest flight from both feet counted as a jump
LEAP_FLIGHT = 0.35         # s: a flight this long is a jump from any take-off
TAKEOFF = 0.1              # s: both feet down this shortly before the flight
JUMP_FORWARD = 0.35        # L of horizontal travel from take-off to landing
JUMP_RISE = 0.05           # L: the pelvis rises at least this in the flight
JUMP_SERIES = 1.5          # s: jumps closer than this are one series ("jumps 3 times")
JUMP_DOWN = 0.25           # L: landing this far below the take-off
G_LEGS = 9.81 / 0.85       # L/s^2: gravity in leg lengths (an adult's leg of 0.85 m)
BALLISTIC = 0.5            # share of gravity a flight's fitted fall reaches at least
BALLISTIC_FRAMES = 6       # frames a flight needs before its fall is fitted
MIN_TURN = 45.0            # deg
TURN_WINDOW = 4.0          # s: a turn is done within this
TURN_RATE = 20.0           # deg/s: facing changing faster than this is turning
SPIN_TURN = 270.0          # deg
SPIN_RATE = 270.0          # deg/s
TWIST_GAP = 0.5            # s: a turn undone within this...
TWIST_LEFT = 30.0          # deg: ...to within this of where it began is a twist
LEVEL_STEP = 0.18          # L: a change of support height that counts (a stair is ~0.2 L)
LEVEL_CLIMB = 0.5          # L: a rise (or descent) this large is a climb


def froude(speed_ms: float, leg: float) -> float:
    return speed_ms ** 2 / (GRAVITY * leg)


def speed_word(gait_label: str, fr: float) -> str | None:
    """"slowly", "briskly", ... or None (an ordinary pace) from a Froude number."""
    if gait_label == "walk":
        return "slowly" if fr < WALK_SLOW else "briskly" if fr > WALK_BRISK else None
    if gait_label == "run":
        return "fast" if fr > SPRINT_FROM else None
    return None


def _direction(body: Body, a: int, b: int) -> tuple[str, float]:
    """("forward" | "backwards" | "left" | "right", median angle of travel to facing)."""
    v = body.ground_velocity[a:b]
    f = body.forward[a:b]
    ang = np.degrees(np.arctan2(f[:, 0] * v[:, 1] - f[:, 1] * v[:, 0],
                                (f * v).sum(axis=1)))   # + : travel to the body's right
    moving = np.linalg.norm(v, axis=1) > TRAVEL * body.leg
    a_med = float(np.degrees(np.angle(np.mean(np.exp(1j * np.radians(ang[moving]))))) if
                  moving.any() else 0.0)
    if abs(a_med) >= BACKWARDS:
        return "backwards", a_med
    if abs(a_med) >= SIDEWAYS:
        return ("right" if a_med > 0 else "left"), a_med
    return "forward", a_med


def _path(body: Body, a: int, b: int) -> tuple[str, float]:
    """("straight" | "curving left" | "curving right" | "in a circle", degrees turned)."""
    v = body.ground_velocity[a:b]
    moving = np.linalg.norm(v, axis=1) > TRAVEL * body.leg
    if moving.sum() < 3:
        return "straight", 0.0
    if float(body.ground_speed[a:b].sum()) / body.fps < CURVE_DISTANCE:
        return "straight", 0.0
    heading = np.unwrap(np.arctan2(v[moving, 0], v[moving, 1]))
    turned = float(np.degrees(heading[-1] - heading[0]))
    if abs(turned) >= CIRCLE:
        return "in a circle", turned
    if abs(turned) >= CURVE:
        return ("curving left" if turned > 0 else "curving right"), turned
    return "straight", turned


def travel(body: Body) -> list[Finding]:
    """The spans of travel with gait, speed word, direction and path (module docstring)."""
    out: list[Finding] = []
    mask = clean_mask(body.ground_speed > TRAVEL, body.fps, min_len=MIN_TRAVEL, max_gap=0.3)
    for a, b in (part for span in runs(mask) for part in _by_gait(body, *span)):
        pad = body.frames(0.25)
        lo, hi = max(0, a - pad), min(body.n, b + pad)
        g = gait(body.p[lo:hi], body.fps)
        speed = float(np.median(np.linalg.norm(body.ground_velocity[a:b], axis=1)))
        fr = froude(speed, body.leg)
        # above a Froude number of 1 the body would leave the ground vaulting over a stiff
        # leg (gravity cannot bend its path enough): no one walks that fast
        label = "run" if g.run_score > 0 or fr >= WALK_LIMIT else "walk"
        direction, angle = _direction(body, a, b)
        path, turned = _path(body, a, b)
        steps = int(sum(len(runs(body.contacts[i, a:b])) for i in range(2)))
        lifts = int(sum(len(runs(~body.contacts[i, a:b])) for i in range(2)))
        distance = float(body.ground_speed[a:b].sum()) / body.fps    # path length, L
        if distance < MIN_DISTANCE or lifts < MIN_LIFTS:
            continue    # swaying, shuffling on the spot, a glide without steps
        if float(body.contacts[:, a:b].any(axis=0).mean()) < FOOT_BORNE:
            continue    # carried by something else: hand over hand along a bar, a swing
        if float(np.median(body.trunk_tilt[a:b])) > UPRIGHT or \
                float(np.median(body.pelvis_height[a:b])) < UPRIGHT_PELVIS:
            continue    # walking and running are upright: a roll or a crawl travels too
        c = confidence(float(np.median(body.ground_speed[a:b])), TRAVEL, 0.5,
                       duration=(b - a) / body.fps, full_after=MIN_TRAVEL)
        # the gait itself is only as sure as the feet: a score near 0 is either
        c = min(c, 0.5 + 0.5 * min(1.0, max(abs(g.run_score), fr - WALK_LIMIT)))
        if c < MIN_CONFIDENCE:
            continue
        out.append(Finding("locomotion", label, body.t(a), body.t(b), "gait score of feet, "
                           "bounce and Froude number (run > 0)", g.run_score, 0.0, c, detail={
                               "speed": speed_word(label, fr), "speed_ms": speed,
                               "froude": fr,
                               "direction": direction, "angle": angle, "path": path,
                               "turned": turned, "steps": steps}))
    return out


def _ahead(body: Body) -> np.ndarray:
    """(T,) how far the left ankle is ahead of the right, in the facing direction, L."""
    ahead = [body.to_body_frame(body.joint(a) - body.joint("root"))[:, 2] / body.leg
             for a in ("LA", "RA")]
    return np.asarray(ahead[0] - ahead[1])


def striding(body: Body) -> np.ndarray:
    """(T,) frames within :data:`STRIDE_WINDOW` s of which the left ankle's place ahead of
    the right changes by :data:`STRIDE_SWING` or more: legs that walk, whether or not the
    root goes anywhere."""
    d, w = _ahead(body), body.frames(STRIDE_WINDOW)
    return np.asarray(maximum_filter1d(d, w, mode="nearest") -
                      minimum_filter1d(d, w, mode="nearest") >= STRIDE_SWING)


def stepping(body: Body) -> np.ndarray:
    """(T,) frames within :data:`STRIDE_WINDOW` s of which each foot in turn was raised
    :data:`STEP_LIFT` leg lengths or more above the other: feet that step, forward or not
    (marching on the spot, side steps held in place), which no standing body does."""
    lift = (body.foot_low - body.foot_low.min(axis=0)[None]) / body.leg
    w = body.frames(STRIDE_WINDOW)
    up = [maximum_filter1d((lift[i] > STEP_LIFT).astype(np.uint8), w, mode="nearest") > 0
          for i in range(2)]
    return np.asarray(up[0] & up[1])


def foot_passes(lead: np.ndarray, margin: float) -> int:
    """How often the leading foot changes in ``lead`` (T,), how far the left ankle is ahead
    of the right (L): crossing ``margin`` one way, then the other (so that a tremor about
    0 is no step)."""
    side, passes = 0, 0
    for x in lead:
        now = 1 if x > margin else -1 if x < -margin else side
        passes += int(side != 0 and now != side)
        side = now
    return passes


def in_place(body: Body) -> list[Finding]:
    """Walks (or runs) in place: upright, the root not travelling, the feet striding
    (:func:`striding`) for :data:`IN_PLACE_MIN` s or more, with steps."""
    still = body.ground_speed < TRAVEL
    upright = (body.trunk_tilt < UPRIGHT) & (body.pelvis_height > UPRIGHT_PELVIS)
    mask = clean_mask(striding(body) & still & upright, body.fps, min_len=IN_PLACE_MIN,
                      max_gap=0.3)
    out = []
    d = _ahead(body)
    for a, b in runs(mask):
        # a step where one foot passes the other, and the first step (as rate._steps counts)
        steps = foot_passes(d[a:b] - np.median(d[a:b]), PASS_MARGIN) + 1
        if steps < 2 * MIN_LIFTS:
            continue
        swing = float(np.percentile(d[a:b], 95) - np.percentile(d[a:b], 5))
        low = body.foot_low.min(axis=0)[a:b] / body.leg
        rise = float(np.percentile(low, 90) - np.percentile(low, 10))
        cadence = steps * body.fps / (b - a)
        running = rise >= IN_PLACE_FLIGHT and cadence >= IN_PLACE_CADENCE
        c = confidence(swing, STRIDE_SWING, 0.5, duration=(b - a) / body.fps,
                       full_after=IN_PLACE_MIN)
        if c < MIN_CONFIDENCE:
            continue
        out.append(Finding("locomotion", "run" if running else "walk", body.t(a),
                           body.t(b), "fore-aft swing of the feet past each other, the "
                           "root still (L)", swing, STRIDE_SWING, c, detail={
                               "speed": None, "direction": None, "path": "straight",
                               "in_place": True, "steps": steps, "cadence": cadence,
                               "flight_rise": rise}))
    return out


_DIRECTIONS = ("forward", "backwards", "left", "right")


def _by_gait(body: Body, a: int, b: int) -> list[tuple[int, int]]:
    """A span of travel cut where the gait or the direction changes (a walk that breaks
    into a run, steps forward then sideways): the gait and direction of overlapping
    :data:`GAIT_WINDOW` s windows, changes that hold for :data:`GAIT_HOLD` s or more."""
    w, hop = body.frames(GAIT_WINDOW), body.frames(GAIT_WINDOW / 4)
    if b - a < 2 * body.frames(GAIT_HOLD) or b - a < w:
        return [(a, b)]
    starts = list(range(a, b - w + 1, hop))
    kinds = np.array([2 * _DIRECTIONS.index(_direction(body, s, s + w)[0]) + int(
        gait(body.p[s:s + w], body.fps).run_score > 0 or froude(
            float(np.median(np.linalg.norm(body.ground_velocity[s:s + w], axis=1))),
            body.leg) >= WALK_LIMIT) for s in starts])
    cell = np.zeros(b - a, dtype=int)
    for s, k in zip(starts, kinds):              # each frame: the window centred nearest
        centre = s + w // 2 - a
        cell[max(0, centre - hop):centre + hop] = k
    cell[:starts[0] + w // 2 - a] = kinds[0]
    cell[starts[-1] + w // 2 - a:] = kinds[-1]
    cuts = [a]
    for lo, _ in runs(np.diff(cell) != 0):
        at = a + lo + 1
        if at - cuts[-1] >= body.frames(GAIT_HOLD) and b - at >= body.frames(GAIT_HOLD):
            cuts.append(at)
    return list(zip(cuts, cuts[1:] + [b]))


def ballistic(body: Body, a: int, b: int) -> bool:
    """Whether frames ``a:b`` with no foot on the floor are a flight: the body's mean
    point (a stand-in for its centre of mass) falls as a thrown body does, its fitted
    vertical acceleration at least :data:`BALLISTIC` of gravity's. A body held up by
    something else (on its toes, on a bar) does not fall; too short a span cannot tell
    (True)."""
    if b - a < BALLISTIC_FRAMES:
        return True
    y = body.p[a:b, :, 1].mean(axis=1) / body.leg
    t = np.arange(b - a) / body.fps
    accel = 2.0 * float(np.polyfit(t, y, 2)[0])
    return accel <= -BALLISTIC * G_LEGS


def jumps(body: Body) -> list[Finding]:
    """Jumps (forward, up or down) and hops, as events (module docstring)."""
    c = body.contacts
    none = ~c[0] & ~c[1]
    both = c[0] & c[1]
    before = body.frames(TAKEOFF)
    events: list[tuple[int, int, str, str | None]] = []   # a, b, kind, take-off foot
    for a, b in runs(none):
        if a == 0 or b >= body.n:
            continue
        flight = (b - a) / body.fps
        two = bool(both[max(0, a - before):a].any())
        if flight >= (JUMP_FLIGHT if two else LEAP_FLIGHT):
            events.append((a, b, "jump", None))
        elif not two and flight >= 0.06:
            foot = "left" if c[0, a - 1] else "right"
            land = "left" if c[0, min(b, body.n - 1)] else "right"
            if foot == land:                # off one foot and back onto the same: a hop
                events.append((a, b, "hop", foot))
    out: list[Finding] = []
    hops = [e for e in events if e[2] == "hop"]
    # hops count only in series (a walk's stumble is not hopping)
    for side in ("left", "right"):
        series = [e for e in hops if e[3] == side]
        group: list[tuple[int, int, str, str | None]] = []
        for e in [*series, None]:
            if e is not None and (not group or e[0] - group[-1][1] < body.frames(0.8)):
                group.append(e)
                continue
            if len(group) >= 3:
                out.append(Finding("locomotion", "hop", body.t(group[0][0]), body.t(group[-1][1]),
                                   "hops in a row", float(len(group)), 3.0,
                                   confidence(len(group), 3, 2, duration=1.0), side=side,
                                   count=len(group)))
            group = [e] if e is not None else []
    for a, b, kind, _ in events:
        if kind != "jump":
            continue
        lo, hi = max(0, a - before), min(body.n - 1, b + before)
        drop = float(body.foot_low[:, lo].min() - body.foot_low[:, hi].min()) / body.leg
        # a jump carries the body up and upright (getting up from the floor does not); off
        # a box or a wall it may only fall
        rise = (float(body.p[a:b, 0, 1].max()) - float(body.p[lo, 0, 1])) / body.leg
        if (rise < JUMP_RISE and drop <= JUMP_DOWN) or \
                float(body.trunk_tilt[lo:b].max()) > 50.0:
            continue
        if not ballistic(body, a, b):   # up on the toes, on a bar, on a climbing frame
            continue
        root = body.p[:, 0, [0, 2]]
        dist = float(np.linalg.norm(root[hi] - root[lo])) / body.leg
        direction = "down" if drop > JUMP_DOWN else "forward" if dist > JUMP_FORWARD else "up"
        flight = (b - a) / body.fps
        f = Finding("locomotion", "jump", body.t(a), body.t(b), "flight (s)", flight,
                    JUMP_FLIGHT, confidence(flight, JUMP_FLIGHT, 0.1),
                    detail={"direction": direction, "distance": dist, "drop": drop})
        if f.confidence < MIN_CONFIDENCE:
            continue
        last = out[-1] if out and out[-1].label == "jump" else None
        if last is not None and last.detail["direction"] == direction and \
                f.start - last.end < JUMP_SERIES:   # jumps in a row: one finding, counted
            out[-1] = replace(last, end=f.end, count=last.count + 1,
                              value=max(last.value, flight))
        else:
            out.append(f)
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]


def turns(body: Body) -> list[Finding]:
    """Turns of the facing and spins (module docstring); each turn's signed angle is in
    ``detail["angle"]`` (positive: to the left)."""
    if body.n < 3:
        return []
    yaw = np.degrees(uniform_filter1d(body.yaw, max(1, body.frames(0.3)) | 1, mode="nearest"))
    rate = np.gradient(yaw) * body.fps
    out: list[Finding] = []
    for sign in (1, -1):
        mask = clean_mask(sign * rate > TURN_RATE, body.fps, min_len=0.2, max_gap=0.3)
        for a, b in runs(mask):
            if (b - a) / body.fps > TURN_WINDOW * 3:
                b = a + body.frames(TURN_WINDOW * 3)
            angle = float(yaw[min(b, body.n - 1)] - yaw[a])
            if sign * angle < MIN_TURN:
                continue
            dur = (b - a) / body.fps
            peak = float(np.abs(rate[a:b]).max())
            spin = abs(angle) >= SPIN_TURN and abs(angle) / max(dur, 1e-6) >= SPIN_RATE * 0.5
            label = "spin" if spin else "turn"
            rounded = int(45 * round(abs(angle) / 45))
            out.append(Finding("turn", label, body.t(a), body.t(b), "facing turned (deg)",
                               abs(angle), MIN_TURN, confidence(abs(angle), MIN_TURN, 45.0),
                               side="left" if sign > 0 else "right",
                               count=max(1, int(round(abs(angle) / 360))) if spin else 1,
                               detail={"angle": angle, "rounded": rounded, "peak_rate": peak}))
    found = sorted([f for f in out if f.confidence >= MIN_CONFIDENCE], key=lambda f: f.start)
    # a turn undone at once (left, then as far right within half a second) is a twist of
    # the trunk, as in punching or dribbling, not a change of facing
    twists = set()
    for f, g in zip(found, found[1:]):
        if f.side != g.side and g.start - f.end <= TWIST_GAP and \
                abs(f.detail["angle"] + g.detail["angle"]) < TWIST_LEFT:
            twists |= {id(f), id(g)}
    return [f for f in found if id(f) not in twists]


def support_level(body: Body) -> np.ndarray:
    """(T,) height of the supporting feet over the take's ground, metres, held through the
    frames where no foot is down."""
    c = body.contacts
    low = np.where(c, body.foot_low, np.nan)
    level = np.nanmin(np.where(c.any(axis=0), low, np.inf), axis=0)
    level[~np.isfinite(level)] = np.nan
    idx = np.flatnonzero(np.isfinite(level))
    if not len(idx):
        return np.zeros(body.n)
    filled = np.interp(np.arange(body.n), idx, level[idx])
    return median_filter(filled, size=min(body.frames(0.5), 2 * body.n + 1) | 1,
                         mode="nearest")


def levels(body: Body) -> list[Finding]:
    """Changes of the support height: "up" or "down", a step or a climb (module docstring)."""
    if body.n < body.frames(1.0):
        return []
    lv = support_level(body) / body.leg
    out: list[Finding] = []
    # plateaus: where the level stays within half a step for 0.3 s
    q = np.round(lv / (LEVEL_STEP / 2))
    plateaus: list[tuple[int, int, float]] = []
    a = 0
    for i in range(1, body.n + 1):
        if i == body.n or abs(q[i] - q[a]) > 1:
            if i - a >= body.frames(0.3):
                plateaus.append((a, i, float(np.median(lv[a:i]))))
            a = i
    changes = [(b0 - 1, a1 + 1, l1 - l0, l0, l1)
               for (a0, b0, l0), (a1, b1, l1) in zip(plateaus, plateaus[1:])
               if abs(l1 - l0) >= LEVEL_STEP / 2]
    # one rise (or fall) of several steps within a few seconds is one change of level
    groups: list[list[tuple[int, int, float, float, float]]] = []
    for ch in changes:
        if groups and np.sign(ch[2]) == np.sign(groups[-1][-1][2]) and \
                ch[0] - groups[-1][-1][1] < body.frames(2.0):
            groups[-1].append(ch)
        else:
            groups.append([ch])
    for g in groups:
        a, b = g[0][0], g[-1][1]
        d = g[-1][4] - g[0][3]
        if abs(d) < LEVEL_STEP:
            continue
        # down a ladder or a climbing frame is as much a climb as up it
        label = "climb" if abs(d) >= LEVEL_CLIMB else "step_up" if d > 0 else "step_down"
        out.append(Finding("level", label, body.t(a), body.t(min(b, body.n)),
                           "change of support height (L)", d, LEVEL_STEP,
                           confidence(abs(d), LEVEL_STEP, LEVEL_STEP), count=len(g),
                           detail={"from": g[0][3], "to": g[-1][4],
                                   "direction": "up" if d > 0 else "down"}))
    return [f for f in out if f.confidence >= MIN_CONFIDENCE]

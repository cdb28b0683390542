"""Posture and support, frame by frame: what carries the body and how it is held.

Each rule is a small pure function of a :class:`~motionlang.analysis.body.Body` that returns a
(T,) bool mask; :func:`postures` turns the masks into findings with their evidence. The rules
read geometry that is the same on every body (PoseScript's posecodes and MotionScript take the
same road): heights over the local floor in standing pelvis heights (1 = upright), angles in
degrees, distances in leg lengths.

- **lying**: the trunk near horizontal and the pelvis near the floor (face up or down from the
  chest's normal); crawling low when the body travels so;
- **all fours** (crawling when it travels): trunk tilted forward, both hands and a knee or a
  foot near the floor;
- **kneeling**: a knee on the floor, the trunk more upright than lying;
- **sitting**: pelvis low and still, thighs near horizontal, the feet ahead of the pelvis (on
  a seat) or the legs along the floor;
- **crouching / squatting**: pelvis low over the feet, knees bent, feet on the floor;
- **hanging / climbing**: both hands above the head and neither foot on the floor;
- **on one leg**: one foot down and the other clearly raised, for longer than any step;
- **arms outstretched**: both arms straight and near horizontal;
- **standing**: upright, feet down, not travelling, and the feet neither striding nor
  stepping in place (on a treadmill, or a take with the root's travel taken out, the feet
  swing past each other or step while the root stays).
"""
from __future__ import annotations

import numpy as np

from motionlang.analysis.body import ARMS, LEGS, Body, J
from motionlang.analysis.evidence import MIN_CONFIDENCE, Finding, clean_mask, confidence, runs
from motionlang.analysis.locomotion import BALLISTIC_FRAMES, ballistic, stepping, striding

# thresholds (standing pelvis heights "sph", leg lengths "L", degrees, seconds)
LYING_TILT = 60.0          # deg: trunk this far from vertical
LYING_PELVIS = 0.45        # sph: pelvis at most this high
LYING_CHEST = 0.35         # L: the chest at most this high (not held up on hands and knees)
FOURS_TILT = 45.0          # deg
HAND_NEAR_FLOOR = 0.25     # L: a hand this close to the local floor touches it
KNEE_NEAR_FLOOR = 0.2      # L
SIT_PELVIS = 0.72          # sph: a sitting pelvis is at most this high
SIT_THIGH = 35.0           # deg: thighs at most this far from horizontal
SIT_FEET_AHEAD = 0.45      # L: feet this far ahead of the pelvis (in the facing direction)
STILL = 0.3                # L/s: root slower than this is still
CROUCH_PELVIS = 0.8        # sph: a crouching pelvis is below this
SQUAT_PELVIS = 0.6         # sph: below this a crouch is a squat
CROUCH_KNEE = 50.0         # deg of knee flexion (0 straight)
FOOT_OFF = 0.3             # L: a foot this far above the local floor is off it
HAND_OVER_HAND = 1.0       # L: a hang whose root goes this far moves along hand over hand
ONE_LEG_RAISE = 0.15       # L: the free foot above the standing one's level
ONE_LEG_MIN = 1.0          # s: longer than any single support of a walk
OUTSTRETCHED_ELEV = 30.0   # deg: arms within this of horizontal
OUTSTRETCHED_REACH = 0.85  # share of the arm's length from shoulder to wrist
UPRIGHT_TILT = 30.0        # deg
STAND_PELVIS = 0.88        # sph
MIN_POSTURE = 0.4          # s: a posture held for less is not reported
GAP = 0.2                  # s: flickers of at most this are closed


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cos = (a * b).sum(-1) / np.maximum(np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1),
                                       1e-9)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def knee_flexion(body: Body) -> np.ndarray:
    """(2, T) degrees each knee is bent (0 = straight leg)."""
    out = []
    for h, k, a in LEGS:
        out.append(_angle_deg(body.p[:, h] - body.p[:, k], body.p[:, a] - body.p[:, k]))
    return 180.0 - np.stack(out)


def thigh_elevation(body: Body) -> np.ndarray:
    """(2, T) degrees of each thigh (hip to knee) from horizontal (90 = hanging straight)."""
    out = []
    for h, k, _ in LEGS:
        v = body.p[:, k] - body.p[:, h]
        out.append(np.degrees(np.arcsin(np.clip(-v[:, 1] / np.maximum(
            np.linalg.norm(v, axis=1), 1e-9), -1, 1))))
    return np.stack(out)


def height_over_floor(body: Body, joint: int) -> np.ndarray:
    """(T,) a joint's height over the local floor, leg lengths."""
    return (body.p[:, joint, 1] - body.local_floor) / body.leg


def lying(body: Body) -> np.ndarray:
    return (body.trunk_tilt > LYING_TILT) & (body.pelvis_height < LYING_PELVIS) & \
        (height_over_floor(body, J["BT"]) < LYING_CHEST)


def hands_down(body: Body) -> np.ndarray:
    """(2, T) each hand near the floor."""
    return np.stack([height_over_floor(body, w) < HAND_NEAR_FLOOR for _, _, w in ARMS])


def knees_down(body: Body) -> np.ndarray:
    """(2, T) each knee near the floor."""
    return np.stack([height_over_floor(body, k) < KNEE_NEAR_FLOOR for _, k, _ in LEGS])


def all_fours(body: Body) -> np.ndarray:
    hands = hands_down(body).all(axis=0)
    support = knees_down(body).any(axis=0) | body.contacts.any(axis=0)
    return (body.trunk_tilt > FOURS_TILT) & hands & support & ~lying(body)


def kneeling(body: Body) -> np.ndarray:
    return knees_down(body).any(axis=0) & (body.trunk_tilt < FOURS_TILT) & \
        (body.pelvis_height < CROUCH_PELVIS)


def _feet_ahead(body: Body) -> np.ndarray:
    """(T,) how far the ankles are ahead of the pelvis along the facing, leg lengths."""
    ankles = body.p[:, [J["LA"], J["RA"]]][:, :, [0, 2]].mean(axis=1)
    return ((ankles - body.p[:, 0, [0, 2]]) * body.forward).sum(axis=1) / body.leg


def sitting(body: Body) -> np.ndarray:
    thighs_level = np.abs(thigh_elevation(body)).min(axis=0) < SIT_THIGH
    low = body.pelvis_height < SIT_PELVIS
    still = body.ground_speed < STILL
    ahead = _feet_ahead(body) > SIT_FEET_AHEAD
    return low & thighs_level & still & ahead & (body.trunk_tilt < LYING_TILT) & \
        ~knees_down(body).any(axis=0) & ~hands_down(body).all(axis=0)


def crouching(body: Body) -> np.ndarray:
    bent = knee_flexion(body).min(axis=0) > CROUCH_KNEE
    feet = body.contacts.any(axis=0)
    return (body.pelvis_height < CROUCH_PELVIS) & bent & feet & ~sitting(body) & \
        ~kneeling(body) & ~lying(body) & ~all_fours(body)


def hanging(body: Body) -> np.ndarray:
    # the floor under a body held by its hands stays where its feet last stood
    # (``Body.local_floor``): feet off it are off the floor, whatever the floor's height
    off = (body.foot_low - body.local_floor[None] > FOOT_OFF * body.leg).all(axis=0)
    return body.hands_overhead & off


def one_leg(body: Body) -> np.ndarray:
    """(T,) bool: balancing on one leg (the side is read by :func:`postures`)."""
    c = body.contacts
    low = body.foot_low
    raised = np.stack([(c[i] & ~c[1 - i]) & (low[1 - i] - low[i] > ONE_LEG_RAISE * body.leg)
                       for i in range(2)]).any(axis=0)
    return raised & (body.ground_speed < 2 * STILL)


def outstretched(body: Body) -> np.ndarray:
    ok = []
    for side, (s, _e, w) in enumerate(ARMS):
        v = body.p[:, w] - body.p[:, s]
        reach = np.linalg.norm(v, axis=1) / body.arm_length(side)
        elev = np.degrees(np.arcsin(np.clip(v[:, 1] / np.maximum(np.linalg.norm(v, axis=1),
                                                                  1e-9), -1, 1)))
        ok.append((reach > OUTSTRETCHED_REACH) & (np.abs(elev) < OUTSTRETCHED_ELEV))
    # lying, arms along the body are level too: that is no holding them out
    return np.asarray(np.stack(ok).all(axis=0) & ~lying(body))


def standing(body: Body) -> np.ndarray:
    return (body.trunk_tilt < UPRIGHT_TILT) & (body.pelvis_height > STAND_PELVIS) & \
        body.contacts.any(axis=0) & (body.ground_speed < 2 * STILL) & ~striding(body) & \
        ~stepping(body)


def _spans(body: Body, mask: np.ndarray, min_len: float = MIN_POSTURE) -> list[tuple[int, int]]:
    return runs(clean_mask(mask, body.fps, min_len=min_len, max_gap=GAP))


def postures(body: Body) -> list[Finding]:
    """Every posture the body holds long enough, as findings (module docstring)."""
    out: list[Finding] = []
    sph = body.pelvis_height
    tilt = body.trunk_tilt

    def add(label: str, a: int, b: int, measure: str, value: float, threshold: float,
            scale: float, side: str | None = None, full: float = 1.0, **detail) -> None:
        c = confidence(value, threshold, scale, duration=(b - a) / body.fps, full_after=full)
        if c >= MIN_CONFIDENCE:
            out.append(Finding("posture", label, body.t(a), body.t(b), measure, value,
                               threshold, c, side=side, detail=detail))

    for a, b in _spans(body, lying(body)):
        face = "up" if np.median(body.chest_normal[a:b, 1]) > 0 else "down"
        # a body that travels along the floor lying face down crawls (on belly or elbows);
        # face up, the pelvis shifts while sitting up, which is no travel
        moving = face == "down" and float(np.median(body.ground_speed[a:b])) > STILL
        add("crawl" if moving else "lie", a, b, "trunk tilt from vertical (deg)",
            float(np.median(tilt[a:b])), LYING_TILT, 20.0, face=face)
    fours = all_fours(body)
    for a, b in _spans(body, fours):
        moving = float(np.median(body.ground_speed[a:b])) > STILL
        add("crawl" if moving else "all_fours", a, b, "trunk tilt from vertical (deg)",
            float(np.median(tilt[a:b])), FOURS_TILT, 20.0)
    kd = knees_down(body)
    for a, b in _spans(body, kneeling(body)):
        both = float(kd[:, a:b].all(axis=0).mean()) > 0.5
        side = "both" if both else ("left" if kd[0, a:b].mean() > kd[1, a:b].mean() else "right")
        add("kneel", a, b, "pelvis height (standing = 1)", float(np.median(sph[a:b])),
            CROUCH_PELVIS, -0.2, side=side)
    for a, b in _spans(body, sitting(body)):
        floor = float(np.median(sph[a:b])) < 0.3
        add("sit", a, b, "pelvis height (standing = 1)", float(np.median(sph[a:b])),
            SIT_PELVIS, -0.2, seat="floor" if floor else "seat")
    for a, b in _spans(body, crouching(body)):
        v = float(np.median(sph[a:b]))
        add("squat" if v < SQUAT_PELVIS else "crouch", a, b, "pelvis height (standing = 1)",
            v, CROUCH_PELVIS, -0.15)
    for a, b in _spans(body, hanging(body)):
        if b - a >= BALLISTIC_FRAMES and ballistic(body, a, b):
            continue    # the hands overhead in a flight (a back flip) carry nothing
        # hand over hand along a bar: the root goes somewhere while the hands carry it
        along = float(np.linalg.norm(body.p[b - 1, 0, [0, 2]] - body.p[a, 0, [0, 2]])) / body.leg
        add("hang", a, b, "lowest foot over the floor (L)",
            float(np.median((body.foot_low.min(axis=0)[a:b] - body.local_floor[a:b])
                            / body.leg)), 0.0, 0.3, travelled=along >= HAND_OVER_HAND)
    ol = one_leg(body)
    for a, b in _spans(body, ol, ONE_LEG_MIN):
        c = body.contacts[:, a:b]
        side = "left" if c[0].mean() > c[1].mean() else "right"
        gap = float(np.median(np.abs(body.foot_low[0, a:b] - body.foot_low[1, a:b]))) / body.leg
        add("one_leg", a, b, "free foot raised (L)", gap, ONE_LEG_RAISE, 0.15, side=side,
            full=ONE_LEG_MIN)
    for a, b in _spans(body, outstretched(body), 0.5):
        add("arms_out", a, b, "share of frames with both arms straight and level",
            float(outstretched(body)[a:b].mean()), 0.5, 0.5)
    for a, b in _spans(body, standing(body), 0.8):
        add("stand", a, b, "pelvis height (standing = 1)", float(np.median(sph[a:b])),
            STAND_PELVIS, 0.1)
    return out

"""Stepping locomotion: walk and run (forward, backward, sideways, in a circle) and turning
on the spot, from a footstep plan.

Plan: a path ``u -> (centre, heading)`` (a line, a circle arc, or a rotation in place) and
N footsteps at path parameters ``u_i``, alternating feet; the last step closes the feet
side by side, so "N steps" means N foot placements. Each foot is planted (flat, heel
strike and heel rise pivoting on heel or ball) or swinging along an arc to its next plant.
The pelvis passes over the middle of the feet at each landing (monotone cubic through those
anchors) with a sideways sway toward the supporting foot. Legs then come from IK, so
planted feet do not slide. Arm swing follows the legs in opposition.
"""
from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.ndimage import gaussian_filter1d

from motionlang.datasets.synth.body import (SIDES, Body, ankle_from_contact,
                                            heading_vectors, smoothstep)
from motionlang.datasets.synth.track import FPS, Stance, Track, limit_reach, rest_upper

# step length (m for a 1.75 m subject), step time (s), swing time / step time
GAIT = {
    ("walk", "slow"): (0.52, 0.66, 0.80), ("walk", "normal"): (0.66, 0.55, 0.80),
    ("walk", "fast"): (0.80, 0.46, 0.80),
    ("run", "slow"): (0.80, 0.36, 1.30), ("run", "normal"): (1.00, 0.33, 1.35),
    ("run", "fast"): (1.25, 0.30, 1.40),
}


def _path(stance: Stance, direction: str, side: str | None, radius: float):
    """``u -> (centre (2,), heading)``; u is metres along the path (radians for "turn")."""
    c0, psi0 = stance.center, stance.yaw
    f0, l0 = heading_vectors(psi0)
    if direction in ("forward", "backward", "left", "right"):
        d = {"forward": f0, "backward": -f0, "left": l0, "right": -l0}[direction]
        return lambda u: (c0 + u * d, psi0)
    sgn = 1.0 if side == "left" else -1.0
    if direction == "turn":
        return lambda u: (c0, psi0 + sgn * u)
    pivot = c0 + sgn * radius * l0

    def circle(u):
        phi = sgn * u / radius
        r = c0 - pivot
        c, s = np.cos(phi), np.sin(phi)
        return pivot + np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]]), psi0 + phi
    return circle


def locomotion(body: Body, stance: Stance, style: dict, rng: np.random.Generator, *,
               action: str, direction: str, count: int, speed: str = "normal",
               side: str | None = None, angle: float | None = None) -> tuple[Track, Stance]:
    """One stepping segment.

    Args:
        action: "walk", "run" or "turn" (turning on the spot, ``angle`` degrees).
        direction: forward/backward/left/right/circle (ignored for "turn").
        count: number of foot placements (>= 2), the last one closing the feet.
        side: turn sense for "turn" and "circle" ("left" = counter-clockwise from above).

    Returns:
        the segment's track and the stance it ends in.
    """
    scale = body.height / 1.75
    tempo = style.get("tempo", 1.0)
    kind = "run" if action == "run" else "walk"
    L, Ts, swing = GAIT[(kind, speed or "normal")]
    L *= scale * style.get("stride", 1.0)
    Ts *= tempo
    pitch_strike, pitch_off, clearance = 0.25, 0.45, 0.07 * scale
    if kind == "run":
        pitch_strike, pitch_off, clearance = 0.15, 0.5, 0.16 * scale
    width = 0.105 * body.height
    radius = 1.0
    n = max(2, int(count))
    if action == "turn":
        direction = "turn"
        total = np.deg2rad(angle or 90.0)
        u = [total * min(i, n - 1) / (n - 1) for i in range(1, n + 1)]
        L, swing = total / (n - 1), 0.7
        Ts = 0.5 * tempo
        pitch_strike = pitch_off = 0.0
        clearance = 0.05 * scale
        first = "L" if side == "left" else "R"
    elif direction in ("left", "right"):
        L = 0.36 * scale * (0.8 if speed == "slow" else 1.15 if speed == "fast" else 1.0)
        u = [L * ((i + 1) // 2) for i in range(1, n + 1)]
        swing, pitch_strike, pitch_off = 0.7, 0.0, 0.1
        first = "L" if direction == "left" else "R"
    else:
        if direction == "backward":
            L *= 0.6
            pitch_strike, pitch_off = 0.0, 0.15
        if direction == "circle":
            L *= 0.85
            radius = (n - 1) * L / (2 * np.pi)
        u = [L * min(i, n - 1) for i in range(1, n + 1)]
        first = SIDES[int(rng.integers(2))] if direction != "circle" else (
            "R" if side == "left" else "L")
    path = _path(stance, direction, side, radius)
    Tsw = swing * Ts
    t0 = max(0.25, Tsw - Ts + 0.25)
    t_land = t0 + Ts * np.arange(1, n + 1)
    t_end = t_land[-1] + 0.45
    T = int(round(t_end * FPS)) + 1
    t = np.arange(T) / FPS

    # footsteps per foot: (t_lift, t_land, x, y, yaw)
    plants = {s: [(-np.inf, -np.inf, *stance.feet[s])] for s in SIDES}
    order = [first if i % 2 == 0 else ("R" if first == "L" else "L") for i in range(n)]
    toe_out = 0.06
    for i, (s, ui) in enumerate(zip(order, u)):
        c, yaw = path(ui)
        _, lv = heading_vectors(yaw)
        lat = lv if s == "L" else -lv
        xy = c + lat * width / 2
        plants[s].append((t_land[i] - Tsw, t_land[i], xy[0], xy[1],
                          yaw + (toe_out if s == "L" else -toe_out)))

    ankle, fyaw, fpitch, contact = {}, {}, {}, {}
    for s in SIDES:
        ankle[s], fyaw[s], fpitch[s], contact[s] = _foot_track(
            body, plants[s], t, Ts, pitch_strike, pitch_off, clearance,
            0.45 if kind == "walk" else 0.35)

    # pelvis: over the middle of the feet at each landing (walking), closer to the
    # landing foot when running
    k = 0.5 if kind == "walk" else 0.3
    anchors_t = [0.0, max(t0 + Ts - Tsw - 0.05, 0.01)]
    anchors = [np.r_[stance.center, stance.yaw]] * 2
    for i in range(n):
        u_prev = u[i - 1] if i > 0 else 0.0
        c, yaw = path(u[i] - k * (u[i] - u_prev))
        anchors_t.append(t_land[i])
        anchors.append(np.r_[c, yaw])
    anchors_t.append(t_end)
    anchors.append(np.r_[path(u[-1])[0], path(u[-1])[1]])
    last = {s: plants[s][-1][2:] for s in SIDES}
    anchors = np.array(anchors)
    pel = PchipInterpolator(np.array(anchors_t), anchors, axis=0)(t)
    single = contact["L"].astype(float) - contact["R"].astype(float)
    sway = gaussian_filter1d(single, 0.3 * Ts * FPS, mode="nearest")
    sway_amp = (0.025 if kind == "walk" else 0.012) * scale * style.get("sway", 1.0)
    _, lv = heading_vectors(pel[:, 2])
    root_pos = np.zeros((T, 3))
    root_pos[:, :2] = pel[:, :2] + sway_amp * sway[:, None] * lv
    # ease posture in and out over 0.3 s so segments join standing ones smoothly
    ramp = smoothstep(np.minimum(t / 0.3, (t_end - t) / 0.3))
    drop = 0.004 + (0.006 if kind == "walk" else 0.056) * ramp
    root_pos[:, 2] = body.pelvis_height - drop * scale
    if kind == "run":
        airborne = gaussian_filter1d((~(contact["L"] | contact["R"])).astype(float), 3)
        root_pos[:, 2] += 0.05 * scale * airborne
    # which leg is ahead: +1 right foot forward ... -1 left foot forward
    fwd, _ = heading_vectors(pel[:, 2])
    rel = {s: np.sum((ankle[s][:, :2] - root_pos[:, :2]) * fwd, axis=1) for s in SIDES}
    swing_sig = np.clip((rel["R"] - rel["L"]) / max(L if action != "turn" else 0.3, 0.2),
                        -1.2, 1.2)
    stepping = kind == "walk" and action != "turn" and direction not in ("left", "right")
    root_rot = np.zeros((T, 3))
    # the pelvis turns with the forward leg, the thorax turns back against it
    root_rot[:, 0] = pel[:, 2] + (0.06 * swing_sig if stepping else 0.0)
    lean = {"walk": -0.04, "run": -0.14}[kind] * (1.4 if speed == "fast" else 1.0)
    root_rot[:, 2] = lean * ramp
    track = Track(root_pos, root_rot, ankle, fyaw, fpitch, contact, rest_upper(T, style))
    limit_reach(body, track)

    # arms swing opposite to the legs
    amp = (0.35 if kind == "walk" else 0.6) * style.get("arm_amp", 1.0)
    if action == "turn" or direction in ("left", "right"):
        amp *= 0.3
    up = track.upper
    for s, sg in (("L", 1.0), ("R", -1.0)):
        up[f"{s}Sx_joint"] += sg * amp * swing_sig - (0.1 * ramp if kind == "run" else 0.0)
        up[f"{s}Ex_joint"] += 0.25 * amp * np.maximum(sg * swing_sig, 0) + (
            1.1 * ramp if kind == "run" else 0.0)
    if stepping:
        up["BTz_joint"] -= 0.1 * swing_sig
    end = Stance({s: tuple(last[s]) for s in SIDES}, float(path(u[-1])[1]))
    return track, end


def _foot_track(body: Body, seq: list, t: np.ndarray, Ts: float, pitch_strike: float,
                pitch_off: float, clearance: float, peak: float):
    """Ankle (T, 3), yaw, pitch and contact (T,) of one foot from its plants.

    ``seq``: [(t_lift, t_land, x, y, yaw)] of the foot's successive plants (the first one
    standing since -inf). Planted: heel strike (toes up, pivot on the heel) easing to flat,
    then heel rise pivoting on the ball before lift-off. Swinging: from the lift-off pose
    to the landing pose along an arc ``clearance`` high at fraction ``peak`` of the swing.
    """
    T = len(t)
    point, Y, P = np.zeros((T, 3)), np.zeros(T), np.zeros(T)
    C = np.zeros(T, bool)
    swings = []
    for k, (_, land, x, y, yaw) in enumerate(seq):
        lift = seq[k + 1][0] if k + 1 < len(seq) else np.inf
        m = (t >= land) & (t < lift)
        if m.any():
            tm = t[m]
            strike = pitch_strike * (1 - smoothstep((tm - land) / 0.12)) if k > 0 else 0 * tm
            if np.isfinite(lift):
                W = min(0.35 * Ts, 0.5 * (lift - max(land, 0.0)))
                rise = -pitch_off * smoothstep((tm - (lift - W)) / W)
            else:
                rise = 0 * tm
            P[m] = np.where(rise < 0, rise, strike)
            Y[m], C[m] = yaw, True
            point[m, :2] = [x, y]
        if k + 1 < len(seq):
            swings.append((seq[k], seq[k + 1]))
    ball = P < 0
    f, _ = heading_vectors(Y[ball])
    point[ball, :2] += f * body.foot_len
    A = ankle_from_contact(body, point, Y, P, ball)
    if swings:  # lift-off and landing poses of all swings at once
        n = len(swings)
        start = np.array([[a[2], a[3], 0.0] for a, _ in swings])
        syaw = np.array([a[4] for a, _ in swings])
        f0, _ = heading_vectors(syaw)
        start[:, :2] += f0 * body.foot_len
        a0 = ankle_from_contact(body, start, syaw, np.full(n, -pitch_off), np.ones(n, bool))
        end = np.array([[b[2], b[3], 0.0] for _, b in swings])
        eyaw = np.array([b[4] for _, b in swings])
        a1 = ankle_from_contact(body, end, eyaw, np.full(n, pitch_strike), np.zeros(n, bool))
        for i, ((_, _, _, _, yaw), (nl, nland, _, _, nyaw)) in enumerate(swings):
            m = (t >= nl) & (t < nland)
            if not m.any():
                continue
            sw = (t[m] - nl) / (nland - nl)
            # lift off and set down vertically: the foot travels only in the middle
            # 80 % of the swing, so it is clear of the floor whenever it moves
            e = smoothstep((sw - 0.1) / 0.8)[:, None]
            A[m] = a0[i] * (1 - e) + a1[i] * e
            # arc peaking at ``peak`` of the swing; finite slope at both ends
            A[m, 2] += clearance * np.sin(0.5 * np.pi * np.where(
                sw < peak, sw / peak, (1 - sw) / (1 - peak)))
            Y[m] = yaw + np.angle(np.exp(1j * (nyaw - yaw))) * e[:, 0]
            P[m] = -pitch_off + (pitch_strike + pitch_off) * e[:, 0]
    return A, Y, P, C

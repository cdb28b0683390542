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

from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import gaussian_filter1d

from motionlang.datasets.synth.body import (
    SIDES,
    Body,
    ankle_from_contact,
    heading_vectors,
    smoothstep,
)
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


@dataclass
class _Plan:
    """A stepping segment's footstep plan: gait constants and ``n`` foot placements at path
    parameters ``u`` (m; radians for "turn"), the first by foot ``first``, and its timing."""
    action: str
    kind: str            # "walk" or "run" ("turn" steps like a walk)
    direction: str       # "turn" when turning on the spot
    speed: str
    scale: float         # body height / 1.75 m
    L: float             # step length (m; radians for "turn")
    Ts: float            # step time (s)
    swing: float         # swing time / step time
    pitch_strike: float  # rad, toes up at heel strike
    pitch_off: float     # rad, heel up at lift-off
    clearance: float     # m, height of the swing arc
    radius: float = 1.0  # m, of a circle path
    n: int = 2
    u: list = field(default_factory=list)
    first: str = "L"
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))  # frame times (T,) s
    t_land: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n,) s
    Tsw: float = 0.0     # swing time (s)
    t0: float = 0.0      # s, before the first lift-off
    t_end: float = 0.0   # s


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
    p = _plan(body, style, rng, action, direction, count, speed, side, angle)
    path = _path(stance, p.direction, side, p.radius)
    plants = _plants(body, stance, p, path)
    ankle, fyaw, fpitch, contact = {}, {}, {}, {}
    for s in SIDES:
        ankle[s], fyaw[s], fpitch[s], contact[s] = _foot_track(
            body, plants[s], p.t, p.Ts, p.pitch_strike, p.pitch_off, p.clearance,
            0.45 if p.kind == "walk" else 0.35)
    last = {s: plants[s][-1][2:] for s in SIDES}
    pel = _pelvis(stance, p, path)
    # ease posture in and out over 0.3 s so segments join standing ones smoothly
    ramp = smoothstep(np.minimum(p.t / 0.3, (p.t_end - p.t) / 0.3))
    root_pos = _root_position(body, style, p, pel, contact, ramp)
    # which leg is ahead: +1 right foot forward ... -1 left foot forward
    fwd, _ = heading_vectors(pel[:, 2])
    rel = {s: np.sum((ankle[s][:, :2] - root_pos[:, :2]) * fwd, axis=1) for s in SIDES}
    swing_sig = np.clip((rel["R"] - rel["L"]) / max(p.L if action != "turn" else 0.3, 0.2),
                        -1.2, 1.2)
    stepping = p.kind == "walk" and action != "turn" and p.direction not in ("left", "right")
    root_rot = np.zeros((len(p.t), 3))
    # the pelvis turns with the forward leg, the thorax turns back against it
    root_rot[:, 0] = pel[:, 2] + (0.06 * swing_sig if stepping else 0.0)
    lean = {"walk": -0.04, "run": -0.14}[p.kind] * (1.4 if speed == "fast" else 1.0)
    root_rot[:, 2] = lean * ramp
    track = Track(root_pos, root_rot, ankle, fyaw, fpitch, contact, rest_upper(len(p.t), style))
    limit_reach(body, track)
    _swing_arms(track.upper, style, p, swing_sig, ramp, stepping)
    end = Stance({s: tuple(last[s]) for s in SIDES}, float(path(p.u[-1])[1]))
    return track, end


def _plan(body: Body, style: dict, rng: np.random.Generator, action: str, direction: str,
          count: int, speed: str, side: str | None, angle: float | None) -> _Plan:
    """The gait constants of ``action`` at ``speed`` for this body and style, the footstep
    parameters along the path and the segment's timing."""
    scale = body.height / 1.75
    tempo = style.get("tempo", 1.0)
    kind = "run" if action == "run" else "walk"
    L, Ts, swing = GAIT[(kind, speed or "normal")]
    L *= scale * style.get("stride", 1.0)
    Ts *= tempo
    p = _Plan(action, kind, direction, speed, scale, L, Ts, swing, 0.25, 0.45, 0.07 * scale)
    if kind == "run":
        p.pitch_strike, p.pitch_off, p.clearance = 0.15, 0.5, 0.16 * scale
    p.n = n = max(2, int(count))
    if action == "turn":
        p.direction = "turn"
        total = np.deg2rad(angle or 90.0)
        p.u = [total * min(i, n - 1) / (n - 1) for i in range(1, n + 1)]
        p.L, p.swing = total / (n - 1), 0.7
        p.Ts = 0.5 * tempo
        p.pitch_strike = p.pitch_off = 0.0
        p.clearance = 0.05 * scale
        p.first = "L" if side == "left" else "R"
    elif direction in ("left", "right"):
        p.L = 0.36 * scale * (0.8 if speed == "slow" else 1.15 if speed == "fast" else 1.0)
        p.u = [p.L * ((i + 1) // 2) for i in range(1, n + 1)]
        p.swing, p.pitch_strike, p.pitch_off = 0.7, 0.0, 0.1
        p.first = "L" if direction == "left" else "R"
    else:
        if direction == "backward":
            p.L *= 0.6
            p.pitch_strike, p.pitch_off = 0.0, 0.15
        if direction == "circle":
            p.L *= 0.85
            p.radius = (n - 1) * p.L / (2 * np.pi)
        p.u = [p.L * min(i, n - 1) for i in range(1, n + 1)]
        p.first = SIDES[int(rng.integers(2))] if direction != "circle" else (
            "R" if side == "left" else "L")
    p.Tsw = p.swing * p.Ts
    p.t0 = max(0.25, p.Tsw - p.Ts + 0.25)
    p.t_land = p.t0 + p.Ts * np.arange(1, n + 1)
    p.t_end = p.t_land[-1] + 0.45
    p.t = np.arange(int(round(p.t_end * FPS)) + 1) / FPS
    return p


def _plants(body: Body, stance: Stance, p: _Plan, path) -> dict[str, list]:
    """Footsteps per foot, ``[(t_lift, t_land, x, y, yaw)]``, starting with the stance's
    (planted since -inf); feet land ``width`` apart across the path, toes slightly out."""
    width = 0.105 * body.height
    plants = {s: [(-np.inf, -np.inf, *stance.feet[s])] for s in SIDES}
    order = [p.first if i % 2 == 0 else ("R" if p.first == "L" else "L") for i in range(p.n)]
    toe_out = 0.06
    for i, (s, ui) in enumerate(zip(order, p.u)):
        c, yaw = path(ui)
        _, lv = heading_vectors(yaw)
        lat = lv if s == "L" else -lv
        xy = c + lat * width / 2
        plants[s].append((p.t_land[i] - p.Tsw, p.t_land[i], xy[0], xy[1],
                          yaw + (toe_out if s == "L" else -toe_out)))
    return plants


def _pelvis(stance: Stance, p: _Plan, path) -> np.ndarray:
    """(T, 3) pelvis centre x, y and heading: over the middle of the feet at each landing
    (walking), closer to the landing foot when running; monotone cubic between."""
    k = 0.5 if p.kind == "walk" else 0.3
    u = p.u
    anchors_t = [0.0, max(p.t0 + p.Ts - p.Tsw - 0.05, 0.01)]
    anchors = [np.r_[stance.center, stance.yaw]] * 2
    for i in range(p.n):
        u_prev = u[i - 1] if i > 0 else 0.0
        c, yaw = path(u[i] - k * (u[i] - u_prev))
        anchors_t.append(p.t_land[i])
        anchors.append(np.r_[c, yaw])
    anchors_t.append(p.t_end)
    anchors.append(np.r_[path(u[-1])[0], path(u[-1])[1]])
    # scipy.interpolate takes a few tenths of a second to load, which every command would
    # pay (the CLI registers `data synth`) and only making a corpus needs
    from scipy.interpolate import PchipInterpolator
    return PchipInterpolator(np.array(anchors_t), np.array(anchors), axis=0)(p.t)


def _root_position(body: Body, style: dict, p: _Plan, pel: np.ndarray, contact: dict,
                   ramp: np.ndarray) -> np.ndarray:
    """(T, 3) root position: the pelvis path swayed toward the supporting foot, lowered a
    little while stepping (more when running), lifted while airborne."""
    single = contact["L"].astype(float) - contact["R"].astype(float)
    sway = gaussian_filter1d(single, 0.3 * p.Ts * FPS, mode="nearest")
    sway_amp = (0.025 if p.kind == "walk" else 0.012) * p.scale * style.get("sway", 1.0)
    _, lv = heading_vectors(pel[:, 2])
    root_pos = np.zeros((len(p.t), 3))
    root_pos[:, :2] = pel[:, :2] + sway_amp * sway[:, None] * lv
    drop = 0.004 + (0.006 if p.kind == "walk" else 0.056) * ramp
    root_pos[:, 2] = body.pelvis_height - drop * p.scale
    if p.kind == "run":
        airborne = gaussian_filter1d((~(contact["L"] | contact["R"])).astype(float), 3)
        root_pos[:, 2] += 0.05 * p.scale * airborne
    return root_pos


def _swing_arms(up: dict, style: dict, p: _Plan, swing_sig: np.ndarray, ramp: np.ndarray,
                stepping: bool) -> None:
    """Swing the arms of the upper-body angles ``up`` opposite to the legs, in place."""
    amp = (0.35 if p.kind == "walk" else 0.6) * style.get("arm_amp", 1.0)
    if p.action == "turn" or p.direction in ("left", "right"):
        amp *= 0.3
    for s, sg in (("L", 1.0), ("R", -1.0)):
        up[f"{s}Sx_joint"] += sg * amp * swing_sig - (0.1 * ramp if p.kind == "run" else 0.0)
        up[f"{s}Ex_joint"] += 0.25 * amp * np.maximum(sg * swing_sig, 0) + (
            1.1 * ramp if p.kind == "run" else 0.0)
    if stepping:
        up["BTz_joint"] -= 0.1 * swing_sig


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

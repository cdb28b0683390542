"""Whole-body primitives on the spot: stand, squat, bow, jump, kick, stomp.

Each builds a :class:`Track` from keyframed pelvis and foot targets (legs by IK later) and
returns the stance it ends in (the same one, except after a forward jump).
"""
from __future__ import annotations

import numpy as np

from motionlang.datasets.synth.body import (
    SIDES,
    Body,
    ankle_from_contact,
    heading_vectors,
    smoothstep,
)
from motionlang.datasets.synth.track import FPS, Stance, Track, concat_tracks, standing_track

G = 9.81


def keyframes(t: np.ndarray, kt, kv) -> np.ndarray:
    """Ease-in-out interpolation through keyframes (zero velocity at each key).

    Args:
        t: (T,) seconds; kt: (K,) increasing key times; kv: (K,) or (K, d) key values.
    """
    kt = np.asarray(kt, dtype=float)
    kv = np.asarray(kv, dtype=float)
    i = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, len(kt) - 2)
    w = smoothstep((t - kt[i]) / np.maximum(kt[i + 1] - kt[i], 1e-9))
    if kv.ndim > 1:
        w = w[:, None]
    return kv[i] * (1 - w) + kv[i + 1] * w


def _frames(duration: float) -> tuple[int, np.ndarray]:
    T = int(round(duration * FPS)) + 1
    return T, np.arange(T) / FPS


def _shift_pelvis(track: Track, stance: Stance, fwd: np.ndarray, side: np.ndarray) -> None:
    """Move the pelvis by ``fwd`` (T,) metres forward and ``side`` (T,) to the left."""
    f, left = heading_vectors(stance.yaw)
    track.root_pos[:, :2] += fwd[:, None] * f + side[:, None] * left


def stand(body: Body, stance: Stance, style: dict, rng, duration: float) -> tuple[Track, Stance]:
    """Quiet standing with a slow postural sway of a few millimetres."""
    T, t = _frames(duration)
    tr = standing_track(body, stance, T, style)
    ph = rng.uniform(0, 2 * np.pi, 2)
    env = smoothstep(np.minimum(t / 0.3, (t[-1] - t) / 0.3))
    _shift_pelvis(tr, stance, 0.006 * env * np.sin(2 * np.pi * 0.25 * t + ph[0]),
                  0.008 * env * np.sin(2 * np.pi * 0.2 * t + ph[1]))
    return tr, stance


def _repeat(n: int, period: float, lead: float = 0.3) -> tuple[float, list[float]]:
    starts = [lead + k * period for k in range(n)]
    return lead + n * period + lead, starts


def squat(body: Body, stance: Stance, style: dict, rng, count: int,
          speed: str = "normal") -> tuple[Track, Stance]:
    """``count`` squats: hips down and back, trunk forward, arms forward for balance."""
    period = {"slow": 2.6, "normal": 1.9, "fast": 1.3}[speed or "normal"] * style.get("tempo", 1)
    duration, starts = _repeat(count, period)
    T, t = _frames(duration)
    tr = standing_track(body, stance, T, style)
    bump = np.zeros(T)
    for s0 in starts:
        bump = np.maximum(bump, keyframes(t, [s0, s0 + 0.45 * period, s0 + 0.55 * period,
                                              s0 + period], [0, 1, 1, 0]) * (t >= s0))
    depth = 0.36 * body.height * 0.5 * style.get("amp", 1.0)
    tr.root_pos[:, 2] -= depth * bump
    _shift_pelvis(tr, stance, -0.16 * body.height / 1.75 * bump, 0 * bump)
    tr.root_rot[:, 2] -= 0.45 * bump  # lean forward
    for s in SIDES:
        tr.upper[f"{s}Sx_joint"] += 1.3 * bump
        tr.upper[f"{s}Ex_joint"] += 0.1 * bump
    tr.upper["BLNx_joint"] += 0.3 * bump  # keep looking ahead
    return tr, stance


def bow(body: Body, stance: Stance, style: dict, rng, count: int) -> tuple[Track, Stance]:
    """``count`` bows: bend forward at the hips, hold, come back up."""
    period = 2.0 * style.get("tempo", 1)
    duration, starts = _repeat(count, period)
    T, t = _frames(duration)
    tr = standing_track(body, stance, T, style)
    bump = np.zeros(T)
    for s0 in starts:
        bump = np.maximum(bump, keyframes(t, [s0, s0 + 0.35 * period, s0 + 0.6 * period,
                                              s0 + period], [0, 1, 1, 0]) * (t >= s0))
    deep = style.get("amp", 1.0)
    tr.root_rot[:, 2] -= 0.55 * deep * bump
    _shift_pelvis(tr, stance, -0.07 * body.height / 1.75 * deep * bump, 0 * bump)
    tr.upper["BTx_joint"] -= 0.2 * deep * bump
    tr.upper["BLNx_joint"] -= 0.15 * bump
    return tr, stance


def jump(body: Body, stance: Stance, style: dict, rng, count: int,
         direction: str = "in_place") -> tuple[Track, Stance]:
    """``count`` two-footed jumps, in place or forward (0.5-0.8 m each)."""
    scale = body.height / 1.75
    tracks, cur = [], stance
    for k in range(count):
        dist = (rng.uniform(0.45, 0.8) * scale) if direction == "forward" else 0.0
        tr, cur = _one_jump(body, cur, style, rng, dist, first=(k == 0), last=(k == count - 1))
        tracks.append(tr)
    return concat_tracks(tracks), cur


def _one_jump(body, stance, style, rng, dist, first, last):
    scale = body.height / 1.75
    t_fl = rng.uniform(0.32, 0.42)
    lead = 0.3 if first else 0.05
    tc, tto = lead + 0.35, lead + 0.5  # crouch bottom, take-off
    tland = tto + t_fl
    tend = tland + (0.75 if last else 0.45)
    T, t = _frames(tend)
    tr = standing_track(body, stance, T, style)
    h0 = tr.root_pos[0, 2]
    f, _ = heading_vectors(stance.yaw)
    depth = 0.12 * scale
    h_to = h0 + 0.02 * scale
    z = keyframes(t, [0, lead, tc, tto], [h0, h0, h0 - depth, h_to])
    tf = np.clip((t - tto) / t_fl, 0, 1)
    vz = G * t_fl / 2
    z = np.where(t > tto, h_to + vz * (t - tto) - G * (t - tto) ** 2 / 2, z)
    after = keyframes(t, [tland, tland + 0.22, tend], [h_to, h0 - 0.8 * depth, h0])
    z = np.where(t >= tland, after, z)
    tr.root_pos[:, 2] = z
    fwd = dist * tf  # constant horizontal speed in flight
    fwd = fwd + keyframes(t, [0, lead, tc, tto], [0, 0, -0.05 * scale, 0.0]) * (t <= tto)
    _shift_pelvis(tr, stance, fwd, 0 * fwd)
    tr.root_rot[:, 2] -= keyframes(t, [0, lead, tc, tto, tland, tland + 0.22, tend],
                                   [0, 0, 0.35, 0.1, 0.1, 0.3, 0.0])
    pitch_ball = -0.5
    for s in SIDES:
        x, y, yaw = stance.feet[s]
        rise = keyframes(t, [0, tc, tto], [0, 0, pitch_ball]) * (t <= tto)
        land = keyframes(t, [tland, tland + 0.1], [pitch_ball, 0.0]) * (t >= tland)
        pitch = np.where(t < tto, rise, np.where(t < tland, pitch_ball, land))
        ball = pitch < 0
        pt = np.zeros((T, 3))
        pt[:, :2] = [x, y]
        pt[:, :2] += (t >= tland)[:, None] * dist * f
        pt[ball, :2] += f * body.foot_len
        yaws = np.full(T, yaw)
        A = ankle_from_contact(body, pt, yaws, pitch, ball)
        flight = (t > tto) & (t < tland)
        # feet ride with the pelvis in the air, knees tucked a little
        i_to = int(np.searchsorted(t, tto))
        A[flight] = A[i_to] + (tr.root_pos[flight] - tr.root_pos[i_to]) \
            + np.array([0, 0, 0.08 * scale]) * np.sin(np.pi * tf[flight])[:, None]
        tr.ankle[s], tr.foot_pitch[s] = A, pitch
        tr.contact[s] = ~flight
        tr.upper[f"{s}Sx_joint"] += keyframes(
            t, [0, lead, tc, tto, tland, tland + 0.25, tend], [0, 0, -0.6, 1.2, 0.6, 0.2, 0])
        tr.upper[f"{s}Ex_joint"] += 0.3 * smoothstep((h0 - z) / (0.5 * depth))
    new_feet = {s: (stance.feet[s][0] + dist * f[0], stance.feet[s][1] + dist * f[1],
                    stance.feet[s][2]) for s in SIDES}
    return tr, Stance(new_feet, stance.yaw)


def _foot_lift(body, stance, style, rng, side, count, kind):
    """Kick or stomp with one foot ``count`` times; the other foot carries the weight."""
    scale = body.height / 1.75
    leg = body.thigh + body.shank
    period = (1.3 if kind == "kick" else 1.0) * style.get("tempo", 1)
    duration, starts = _repeat(count, period, lead=0.45)
    T, t = _frames(duration)
    tr = standing_track(body, stance, T, style)
    s = "L" if side == "left" else "R"
    f, left = heading_vectors(stance.yaw)
    lat = left if s == "L" else -left
    # weight over the support foot for the whole segment
    shift = keyframes(t, [0, 0.4, duration - 0.4, duration], [0, 1, 1, 0])
    _shift_pelvis(tr, stance, 0 * shift, -np.sign(lat @ left) * 0.05 * scale * shift)
    A0 = tr.ankle[s][0].copy()
    rel_f, rel_z, pitch = np.zeros(T), np.zeros(T), np.zeros(T)
    amp = style.get("amp", 1.0)
    for s0 in starts:
        p = period
        if kind == "kick":
            kt = [s0, s0 + 0.2 * p, s0 + 0.42 * p, s0 + 0.6 * p, s0 + 0.85 * p]
            kf = [0, -0.22 * scale, 0.55 * leg, 0.15 * scale, 0]
            kz = [0, 0.12 * scale, 0.38 * leg * amp, 0.12 * scale, 0]
            kp = [0, -0.3, -0.6, -0.2, 0]
        else:
            kt = [s0, s0 + 0.4 * p, s0 + 0.58 * p, s0 + 0.74 * p, s0 + p]
            kf = [0, 0.08 * scale, 0.08 * scale, 0, 0]
            kz = [0, 0.24 * scale * amp, 0.24 * scale * amp, 0, 0]
            kp = [0, 0.05, 0.05, 0, 0]
        m = (t >= kt[0]) & (t <= kt[-1])
        rel_f[m] = keyframes(t[m], kt, kf)
        rel_z[m] = keyframes(t[m], kt, kz)
        pitch[m] = keyframes(t[m], kt, kp)
        if kind == "stomp":  # the way down is fast, not eased
            d = (t > kt[2]) & (t <= kt[3])
            w = ((t[d] - kt[2]) / (kt[3] - kt[2])) ** 1.6
            rel_z[d] = kz[2] * (1 - w)
            rel_f[d] = kf[2] * (1 - w)
        if kind == "kick":  # lean back a little while kicking
            tr.root_rot[m, 2] += keyframes(t[m], kt, [0, 0.05, 0.15, 0.05, 0])
            opp = "R" if s == "L" else "L"
            tr.upper[f"{opp}Sx_joint"][m] += keyframes(t[m], kt, [0, 0.2, 0.5, 0.2, 0])
            tr.upper[f"{s}Sx_joint"][m] -= keyframes(t[m], kt, [0, 0.1, 0.4, 0.1, 0])
    tr.ankle[s] = A0 + rel_f[:, None] * np.r_[f, 0] + rel_z[:, None] * np.array([0, 0, 1.0])
    tr.foot_pitch[s] = pitch
    tr.contact[s] = rel_z < 0.005
    return tr, stance


def kick(body, stance, style, rng, side: str, count: int) -> tuple[Track, Stance]:
    return _foot_lift(body, stance, style, rng, side, count, "kick")


def stomp(body, stance, style, rng, side: str, count: int) -> tuple[Track, Stance]:
    return _foot_lift(body, stance, style, rng, side, count, "stomp")

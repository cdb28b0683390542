"""Upper-body primitives: wave, punch, wipe, raise arms — as arm-DOF targets blended over
any body segment (standing or walking).

Poses are in the left arm's convention (see :mod:`.body`): ``Sx`` flexes the shoulder
forward/up, ``Sy`` abducts, ``Sz`` rotates about the (flexed) vertical, ``Ex`` bends the
elbow. The right arm gets the mirrored signs.
"""
from __future__ import annotations

import numpy as np

from motionlang.datasets.synth.actions import keyframes
from motionlang.datasets.synth.body import SIDES
from motionlang.datasets.synth.track import FPS, Track

KEYS = ("Sx", "Sy", "Sz", "Ex")


def _sides(side: str) -> tuple[str, ...]:
    return SIDES if side == "both" else ("L" if side == "left" else "R",)


def natural_duration(action: str, count: int, style: dict) -> float:
    """Seconds an upper-body action needs for ``count`` repetitions."""
    tempo = style.get("tempo", 1.0)
    per = {"wave": 0.55, "punch": 0.6, "wipe": 1.0, "raise_arms": 2.0}[action] * tempo
    return 1.0 + per * count


def arm_targets(action: str, side: str, count: int, t: np.ndarray, style: dict, rng
                ) -> tuple[dict[str, np.ndarray], np.ndarray, dict[str, np.ndarray]]:
    """Targets for one upper-body action starting at t=0.

    Returns:
        ({dof: (T,) target radians}, weight (T,) in [0, 1], {dof: (T,) additive offsets}).
    """
    tempo = style.get("tempo", 1.0)
    amp = style.get("amp", 1.0)
    dur = natural_duration(action, count, style)
    w = keyframes(t, [0, 0.5, dur - 0.5, dur], [0, 1, 1, 0]) * (t <= dur)
    tin = np.clip(t - 0.5, 0, None)
    targets: dict[str, np.ndarray] = {}
    extra: dict[str, np.ndarray] = {}
    sides = _sides(side)
    for k, s in enumerate(sides):
        if action == "wave":
            per = 0.55 * tempo
            osc = 0.4 * amp * np.sin(2 * np.pi * tin / per) * (tin < count * per)
            pose = {"Sx": 1.5, "Sy": 1.35, "Sz": 0.0, "Ex": 1.45 + osc}
        elif action == "raise_arms":
            per = 2.0 * tempo
            lift = np.zeros_like(t)
            for r in range(count):
                s0 = r * per
                lift = np.maximum(lift, keyframes(t, [s0, s0 + 0.7 * per / 2, s0 + 0.65 * per,
                                                      s0 + per], [0, 1, 1, 0]) * (t >= s0))
            w = np.maximum(w * 0, lift)
            pose = {"Sx": 2.8 * amp ** 0.3 + 0 * t, "Sy": 0.15, "Sz": 0.0, "Ex": 0.1}
        elif action == "punch":
            per = 0.6 * tempo
            # with both hands the fists alternate
            n_mine = [r for r in range(count) if len(sides) == 1 or r % 2 == k]
            ext = np.zeros_like(t)
            for r in n_mine:
                s0 = 0.5 + r * per
                ext = np.maximum(ext, keyframes(t, [s0, s0 + 0.18 * tempo, s0 + 0.25 * tempo,
                                                    s0 + 0.5 * tempo], [0, 1, 1, 0]) * (t >= s0))
            # guard: fist in front of the chin; punch: arm straight ahead at shoulder height,
            # fist in front of the body's midline (poses fitted by forward kinematics)
            pose = {"Sx": 0.4 + 1.1 * ext, "Sy": 0.2 - 0.2 * ext, "Sz": -0.4 - 0.6 * ext,
                    "Ex": 2.2 - 2.0 * ext}
        elif action == "wipe":
            per = 1.0 * tempo
            osc = np.sin(2 * np.pi * tin / per) * (tin < count * per)
            # hand flat on a table in front of the hips, sweeping sideways
            pose = {"Sx": 0.75 + 0.1 * osc, "Sy": 0.32 + 0.3 * amp * osc, "Sz": 0.2,
                    "Ex": 0.55 - 0.15 * osc}
            extra["BTx_joint"] = -0.25 * w
        else:
            raise ValueError(f"not an upper-body action: {action!r}")
        for key in KEYS:
            sign = 1.0 if (s == "L" or key.endswith("x")) else -1.0
            targets[f"{s}{key}_joint"] = sign * (np.zeros_like(t) + pose[key])
    return targets, w, extra


def apply_upper(track: Track, action: str, side: str, count: int, start: int, style: dict,
                rng) -> int:
    """Blend an upper-body action into ``track`` from frame ``start``; returns its end frame."""
    dur = natural_duration(action, count, style)
    n = min(int(round(dur * FPS)) + 1, track.n_frames - start)
    t = np.arange(n) / FPS
    targets, w, extra = arm_targets(action, side, count, t, style, rng)
    sl = slice(start, start + n)
    for dof, v in targets.items():
        track.upper[dof][sl] = (1 - w) * track.upper[dof][sl] + w * v
    for dof, v in extra.items():
        track.upper[dof][sl] += v
    return start + n

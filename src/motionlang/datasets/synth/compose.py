"""Random programs of primitives and their realisation as one MMM motion.

A program is 1-3 body primitives in sequence (e.g. walk, turn around, walk), optionally
with one upper-body primitive layered over a walk ("waves while walking"). The motion
starts and ends standing; segments join at standing stances, so transitions are smooth.
"""
from __future__ import annotations

import functools

import numpy as np

from motionlang.datasets.synth import actions, arms, gait
from motionlang.datasets.synth.actions import keyframes
from motionlang.datasets.synth.body import Body
from motionlang.datasets.synth.spec import UPPER_ACTIONS, Primitive
from motionlang.datasets.synth.track import (
    FPS,
    UPPER_DOFS,
    Stance,
    Track,
    concat_tracks,
    solve_track,
)
from motionlang.formats.mmm_model import mmm_skeleton
from motionlang.kinematics.motion import Motion

# action -> relative frequency (walking dominates KIT-ML, so it does here)
ACTION_WEIGHTS = {"walk": 30, "run": 7, "turn": 7, "wave": 7, "kick": 5, "stomp": 4,
                  "squat": 5, "jump": 6, "raise_arms": 5, "bow": 4, "wipe": 4, "punch": 5,
                  "stand": 3}


def _choice(rng, options, p=None):
    if p is not None:
        p = np.asarray(p, dtype=float)
        p = p / p.sum()
    return options[int(rng.choice(len(options), p=p))]


def _speed(rng) -> str:
    return _choice(rng, ("slow", "normal", "fast"), (0.25, 0.5, 0.25))


def random_primitive(rng: np.random.Generator, action: str | None = None,
                     allow: tuple[str, ...] | None = None) -> Primitive:
    """One primitive with random parameters (frames not yet filled in)."""
    if action is None:
        names = [a for a in ACTION_WEIGHTS if allow is None or a in allow]
        action = _choice(rng, names, [ACTION_WEIGHTS[a] for a in names])
    side = _choice(rng, ("left", "right"))
    if action == "walk":
        d = _choice(rng, ("forward", "backward", "left", "right", "circle"),
                    (0.55, 0.13, 0.08, 0.08, 0.16))
        if d == "circle":
            return Primitive("walk", side=side, count=int(rng.integers(10, 15)), direction=d,
                             speed=_speed(rng), angle=360)
        n = int(rng.integers(2, 9)) if d == "forward" else int(rng.integers(2, 7))
        if d in ("left", "right"):
            n += n % 2
        return Primitive("walk", count=n, direction=d, speed=_speed(rng))
    if action == "run":
        if rng.random() < 0.2:
            return Primitive("run", side=side, count=int(rng.integers(12, 17)),
                             direction="circle", speed=_speed(rng), angle=360)
        return Primitive("run", count=int(rng.integers(4, 11)), direction="forward",
                         speed=_speed(rng))
    if action == "turn":
        return Primitive("turn", side=side, angle=int(_choice(rng, (90, 180))))
    if action == "jump":
        return Primitive("jump", count=int(rng.integers(1, 4)),
                         direction=_choice(rng, ("in_place", "forward")))
    if action == "stand":
        return Primitive("stand")
    if action in ("squat", "bow"):
        return Primitive(action, count=int(rng.integers(1, 4)))
    if action in ("kick", "stomp"):
        return Primitive(action, side=side, count=int(rng.integers(1, 4)))
    sides = _choice(rng, ("left", "right", "both"), (0.4, 0.4, 0.2))
    counts = {"wave": (2, 6), "punch": (1, 5), "wipe": (2, 6), "raise_arms": (1, 3)}[action]
    return Primitive(action, side=sides, count=int(rng.integers(*counts)))


def random_program(rng: np.random.Generator) -> list[Primitive]:
    """1-3 body primitives, sometimes with an upper-body action over a walk."""
    r = rng.random()
    if r < 0.5:
        return [random_primitive(rng)]
    if r < 0.65:
        walk = random_primitive(rng, "walk")
        if walk.direction not in ("forward", "backward"):
            walk = Primitive("walk", count=int(rng.integers(3, 8)), direction="forward",
                             speed=_choice(rng, ("slow", "normal")))
        up = random_primitive(rng, _choice(rng, ("wave", "punch", "raise_arms"), (0.6, 0.2, 0.2)))
        up.layer = "upper"
        return [walk, up]
    if r < 0.8:  # the KIT classic: walk, turn around, walk
        w1 = Primitive("walk", count=int(rng.integers(2, 6)), direction="forward",
                       speed=_speed(rng))
        turn = Primitive("turn", side=_choice(rng, ("left", "right")),
                         angle=int(_choice(rng, (90, 180), (0.3, 0.7))))
        w2 = Primitive("walk", count=int(rng.integers(2, 6)), direction="forward",
                       speed=_choice(rng, (w1.speed, _speed(rng))))
        return [w1, turn, w2]
    n = int(rng.integers(2, 4))
    prog: list[Primitive] = []
    while len(prog) < n:
        p = random_primitive(rng)
        if prog and p.action == prog[-1].action:
            continue
        if p.direction == "circle" or (p.count or 0) > 6:
            continue  # keep sequences short
        prog.append(p)
    return prog


def random_style(rng: np.random.Generator) -> dict:
    """Per-sample variation: height, tempo, stride, amplitudes and posture offsets."""
    return {
        "height": round(float(rng.uniform(1.55, 1.95)), 2),
        "tempo": float(rng.uniform(0.9, 1.12)), "stride": float(rng.uniform(0.9, 1.1)),
        "arm_amp": float(rng.uniform(0.7, 1.3)), "sway": float(rng.uniform(0.6, 1.4)),
        "amp": float(rng.uniform(0.8, 1.15)),
        "posture": {"BTx_joint": float(rng.normal(-0.04, 0.03)),
                    "BLNx_joint": float(rng.normal(0.0, 0.05)),
                    "LSy_joint": float(rng.normal(0.0, 0.04)),
                    "RSy_joint": float(rng.normal(0.0, 0.04)),
                    "LEx_joint": float(rng.normal(0.0, 0.1)),
                    "REx_joint": float(rng.normal(0.0, 0.1))},
    }


def _segment(body, stance, style, rng, p: Primitive) -> tuple[Track, Stance]:
    a = p.action
    if a in ("walk", "run"):
        return gait.locomotion(body, stance, style, rng, action=a, direction=p.direction,
                               count=p.count, speed=p.speed, side=p.side)
    if a == "turn":
        n = 3 if p.angle == 90 else int(rng.integers(4, 6))
        return gait.locomotion(body, stance, style, rng, action="turn", direction="turn",
                               count=n, side=p.side, angle=p.angle)
    if a == "stand":
        return actions.stand(body, stance, style, rng, float(rng.uniform(1.5, 3.0)))
    if a == "squat":
        return actions.squat(body, stance, style, rng, p.count)
    if a == "bow":
        return actions.bow(body, stance, style, rng, p.count)
    if a == "jump":
        return actions.jump(body, stance, style, rng, p.count, p.direction)
    if a in ("kick", "stomp"):
        return getattr(actions, a)(body, stance, style, rng, p.side, p.count)
    if a in UPPER_ACTIONS:  # on its own: stand while doing it
        dur = arms.natural_duration(a, p.count, style) + 0.6
        tr, st = actions.stand(body, stance, style, rng, dur)
        arms.apply_upper(tr, a, p.side, p.count, 30, style, rng)
        return tr, st
    raise ValueError(f"unknown action {a!r}")


def build_motion(program: list[Primitive], style: dict, rng: np.random.Generator,
                 skeleton=None) -> tuple[Motion, list[Primitive], Track]:
    """Realise a program as a 100 Hz motion on the MMM skeleton of ``style["height"]``.

    Returns:
        the motion, the program with ``start``/``end`` frames filled in, and the assembled
        track (its ``contact`` flags are the ground-truth foot contacts).
    """
    body = Body(style["height"])
    sk = skeleton or _skeleton(float(style["height"]))
    yaw0 = float(rng.uniform(-np.pi, np.pi))
    stance = Stance.standing(rng.uniform(-1.0, 1.0, 2), yaw0, 0.105 * body.height)
    tracks, out = [], []
    tr, stance = actions.stand(body, stance, style, rng, float(rng.uniform(0.3, 0.8)))
    tracks.append(tr)
    frame = tr.n_frames
    for p in program:
        q = Primitive.from_dict(p.to_dict())
        if p.layer == "upper":
            body_tr, body_start = tracks[-1], out[-1].start
            span = body_tr.n_frames / FPS - 0.4
            # fit the repetitions into the body segment: fewer, then quicker
            while q.count > 1 and arms.natural_duration(q.action, q.count, style) > span:
                q.count -= 1
            up_style = dict(style)
            while arms.natural_duration(q.action, q.count, up_style) > span \
                    and up_style["tempo"] > 0.5:
                up_style["tempo"] *= 0.9
            need = int(round(arms.natural_duration(q.action, q.count, up_style) * FPS))
            off = max(0, (body_tr.n_frames - need) // 2)
            q.start = body_start + off
            q.end = body_start + arms.apply_upper(body_tr, q.action, q.side, q.count, off,
                                                  up_style, rng)
            out.append(q)
            continue
        tr, stance = _segment(body, stance, style, rng, p)
        q.start, q.end = frame, frame + tr.n_frames
        frame += tr.n_frames
        tracks.append(tr)
        out.append(q)
    tr, stance = actions.stand(body, stance, style, rng, float(rng.uniform(0.3, 0.8)))
    tracks.append(tr)
    track = concat_tracks(tracks)
    _add_noise(track, rng)
    angles = solve_track(body, track, sk.dof_names)
    motion = Motion(sk, FPS, track.root_pos, track.root_rot, angles, name="synth",
                    source_format="synthetic",
                    meta={"height": style["height"], "mass": round(float(
                        22.0 * style["height"] ** 2 * rng.uniform(0.85, 1.2)), 1)})
    return motion, out, track


def _add_noise(track: Track, rng: np.random.Generator, amp: float = 0.015,
               knot_s: float = 0.35) -> None:
    """Slow, smooth wobble on the spine, neck and arms (legs stay exact for the feet):
    random values every ``knot_s`` seconds, eased in between."""
    T = track.n_frames
    step = int(knot_s * FPS)
    knots = rng.normal(0.0, amp, size=(T // step + 2, len(UPPER_DOFS)))
    knots[0] = 0.0
    kt = np.arange(len(knots)) * step
    noise = keyframes(np.arange(T, dtype=float), kt, knots)
    for i, n in enumerate(UPPER_DOFS):
        track.upper[n] = track.upper[n] + noise[:, i]


@functools.lru_cache(maxsize=128)
def _skeleton(height: float):
    """MMM skeletons per height, shared (motions never modify their skeleton)."""

    return mmm_skeleton(height)

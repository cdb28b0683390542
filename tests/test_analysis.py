"""The grounded analysis (``motionlang.analysis``): each detector on a body the test builds,
and each shown to say "no" where the body does not do the thing."""
from __future__ import annotations

import numpy as np
import pytest

from helpers.bodies import FPS, SIT, STAND, I, blend, hold, pose, take, turned
from motionlang.analysis import CANNOT_TELL, analyse, analyse_positions, repeats, tidy
from motionlang.analysis.analyse import Analysis
from motionlang.analysis.body import Body, pieces
from motionlang.analysis.evidence import Finding, clean_mask, confidence, runs
from motionlang.analysis.locomotion import ballistic
from motionlang.analysis.sentences import join
from motionlang.analysis.words import actions_named, agrees
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES


def labels(p21, fps: float = FPS) -> list[str]:
    return [f.label for f in analyse_positions(p21, fps).findings]


def test_standing_still_is_standing_and_nothing_else():
    rng = np.random.default_rng(0)
    p = hold(pose(), 3.0) + rng.normal(0, 0.002, (90, 21, 3))   # marker jitter
    a = analyse_positions(p, FPS)
    assert [f.label for f in a.findings] == ["stand"]
    assert a.sentence() == "a person stands still"


def test_sits_down_on_a_seat_and_gets_up():
    p = take(hold(pose(), 1.0), blend(pose(), SIT, 1.0), hold(SIT, 2.0), blend(SIT, pose(), 1.0),
             hold(pose(), 1.0))
    a = analyse_positions(p, FPS)
    sit = [f for f in a.findings if f.label == "sit"]
    assert len(sit) == 1 and sit[0].detail["seat"] == "seat"
    assert 1.3 < sit[0].start < 2.2 and 3.8 < sit[0].end < 4.7
    assert "sits down" in a.sentence()
    assert a.main_action() == "sit"


def test_a_squat_is_not_a_sit():
    """Pelvis low over the feet (no thighs forward to a seat) is a squat, not sitting."""
    sq = pose(root=(0, 0.45, 0), BP=(0, 0.55, 0.02), BT=(0, 0.75, 0.08), BLN=(0, 0.93, 0.12),
              BUN=(0, 1.08, 0.14), LS=(0.18, 0.9, 0.12), RS=(-0.18, 0.9, 0.12),
              LE=(0.2, 0.65, 0.2), RE=(-0.2, 0.65, 0.2), LW=(0.2, 0.5, 0.35),
              RW=(-0.2, 0.5, 0.35), LH=(0.09, 0.43, 0), RH=(-0.09, 0.43, 0),
              LK=(0.12, 0.45, 0.4), RK=(-0.12, 0.45, 0.4))
    p = take(hold(pose(), 1.0), blend(pose(), sq, 0.7), hold(sq, 2.0), blend(sq, pose(), 0.7),
             hold(pose(), 1.0))
    got = labels(p)
    assert "squat" in got or "crouch" in got
    assert "sit" not in got


def test_lying_face_up_from_the_first_frame():
    lie = np.array([[STAND[n][0], 0.12 + 0.02 * (STAND[n][2] > 0), 1.0 - STAND[n][1]]
                    for n in KIT21_NAMES])   # the standing body laid along +Z, face up
    a = analyse_positions(hold(lie, 3.0), FPS)
    found = [f for f in a.findings if f.label == "lie"]
    assert found and found[0].detail["face"] == "up"
    assert a.sentence().startswith("a person lies on the back")


def test_lying_face_down_still_is_lying_and_travelling_so_is_a_crawl():
    up = np.array([[STAND[n][0], 0.12 + 0.02 * (STAND[n][2] > 0), 1.0 - STAND[n][1]]
                   for n in KIT21_NAMES])
    down = up * [-1, -1, 1] + [0, 0.26, 0]   # turned over about its length: face down
    still = analyse_positions(hold(down, 3.0), FPS)
    assert [(f.label, f.detail.get("face")) for f in still.findings] == [("lie", "down")]
    p = hold(down, 3.0).copy()
    p[:, :, 2] -= 0.5 * (np.arange(len(p)) / FPS)[:, None]   # head first, 0.5 m/s
    labels_ = [f.label for f in analyse_positions(p, FPS).findings]
    assert "crawl" in labels_ and "lie" not in labels_
    slid = up[None].repeat(len(p), 0).copy()
    slid[:, :, 2] = p[:, :, 2]   # face up, the same travel: no crawl
    assert "crawl" not in labels(slid)


def test_kneeling_on_both_knees():
    kn = pose(root=(0, 0.5, 0), BP=(0, 0.6, 0), BT=(0, 0.8, 0), BLN=(0, 1.0, 0),
              BUN=(0, 1.15, 0), LS=(0.18, 0.97, 0), RS=(-0.18, 0.97, 0), LE=(0.2, 0.7, 0),
              RE=(-0.2, 0.7, 0), LW=(0.2, 0.45, 0), RW=(-0.2, 0.45, 0), LH=(0.09, 0.48, 0),
              RH=(-0.09, 0.48, 0), LK=(0.09, 0.06, 0.0), RK=(-0.09, 0.06, 0.0),
              LA=(0.09, 0.08, -0.42), RA=(-0.09, 0.08, -0.42), LMrot=(0.09, 0.05, -0.45),
              RMrot=(-0.09, 0.05, -0.45), LF=(0.09, 0.02, -0.3), RF=(-0.09, 0.02, -0.3))
    p = take(hold(pose(), 1.0), blend(pose(), kn, 1.0), hold(kn, 2.0))
    kneel = [f for f in analyse_positions(p, FPS).findings if f.label == "kneel"]
    assert kneel and kneel[0].side == "both"


def _punches(n: int, seconds: float) -> np.ndarray:
    """The right fist driven straight forward ``n`` times, each taking ``seconds``."""
    bent = pose(RE=(-0.22, 1.2, 0.15), RW=(-0.2, 1.38, 0.18))
    straight = pose(RE=(-0.18, 1.42, 0.28), RW=(-0.18, 1.42, 0.54))
    parts = [hold(bent, 0.5)]
    for _ in range(n):
        parts += [blend(bent, straight, seconds), blend(straight, bent, 0.3), hold(bent, 0.3)]
    return take(*parts, hold(bent, 0.5))


def test_punches_are_counted_with_their_side():
    a = analyse_positions(_punches(3, 0.12), FPS)
    punch = [f for f in a.findings if f.label == "punch"]
    assert len(punch) == 1 and punch[0].side == "right" and punch[0].count == 3
    assert a.main_action() == "punch"
    assert "punches with the right hand 3 times" in a.sentence()


def test_a_slow_reach_is_no_punch():
    assert "punch" not in labels(_punches(1, 1.5))


def _thrust_held(seconds: float, back: bool = True) -> np.ndarray:
    """The right fist driven forward as fast as a punch, then held out ``seconds`` (and
    drawn back where ``back``: else the take ends with the arm out)."""
    bent = pose(RE=(-0.22, 1.2, 0.15), RW=(-0.2, 1.38, 0.18))
    straight = pose(RE=(-0.18, 1.42, 0.28), RW=(-0.18, 1.42, 0.54))
    parts = [hold(bent, 0.5), blend(bent, straight, 0.12), hold(straight, seconds)]
    return take(*parts, *((blend(straight, bent, 0.3), hold(bent, 0.5)) if back else ()))


def test_a_punch_is_drawn_back_and_an_arm_held_out_is_none():
    # a jab held out a moment is still a punch; held out 2 s, a push, a point or a shot's
    # follow-through, whether it is drawn back or the take ends with it out
    assert "punch" in labels(_thrust_held(0.5))
    assert "punch" not in labels(_thrust_held(2.0))
    assert "punch" not in labels(_thrust_held(2.0, back=False))
    assert "punch" in labels(_thrust_held(0.3, back=False))


def _sweep(seconds: float, turn: float) -> np.ndarray:
    """The right arm straightening from bent in front while the fist swings ``turn`` radians
    round the shoulder to the side at chest height (a dancer's port de bras; ``turn`` 0: a
    straight thrust forward), the bones kept their lengths."""
    shoulder = np.array(STAND["RS"])
    n = int(round(seconds * FPS))
    frames = []
    for k in np.concatenate([np.zeros(15), np.linspace(0, 1, n), np.ones(15)]):
        r, a = 0.33 + 0.2 * k, turn * k
        hand = shoulder + r * np.array([-np.sin(a), 0.0, np.cos(a)])
        drop = np.sqrt(max(0.27 ** 2 - (r / 2) ** 2, 0.0))   # the elbow below the line
        frames.append(pose(RE=tuple((shoulder + hand) / 2 - [0, drop, 0]), RW=tuple(hand)))
    return np.stack(frames)


def test_an_arm_swept_round_the_shoulder_is_no_punch_though_it_straightens_as_fast():
    assert "punch" in labels(_sweep(0.12, 0.0))
    assert "punch" not in labels(_sweep(0.12, np.pi / 2))


def test_raise_and_wave_and_their_no():
    up = pose(RE=(-0.2, 1.7, 0), RW=(-0.2, 1.95, 0))
    raised = take(hold(pose(), 0.5), blend(pose(), up, 0.5), hold(up, 1.5), blend(up, pose(), 0.5))
    a = analyse_positions(raised, FPS)
    assert [f.side for f in a.findings if f.label == "raise"] == ["right"]
    assert "wave" not in {f.label for f in a.findings}
    t = np.arange(int(3 * FPS)) / FPS
    wave = hold(up, 3.0).copy()
    wave[:, I["RW"], 0] += 0.12 * np.sin(2 * np.pi * 1.5 * t)
    a = analyse_positions(take(hold(pose(), 0.5), wave, hold(pose(), 0.5)), FPS)
    waves = [f for f in a.findings if f.label == "wave"]
    assert waves and waves[0].side == "right" and waves[0].count >= 3
    assert "raise" not in {f.label for f in a.findings}     # said by the wave
    assert "waves with the right hand" in a.sentence()


def test_turns_left_about_90_degrees():
    n = int(4 * FPS)
    yaw = np.radians(90) * np.clip((np.arange(n) / FPS - 1.0) / 1.5, 0, 1)
    a = analyse_positions(turned(hold(pose(), 4.0), yaw), FPS)
    turn = [f for f in a.findings if f.label == "turn"]
    assert len(turn) == 1 and turn[0].side == "left"
    assert turn[0].detail["rounded"] == 90
    a = analyse_positions(turned(hold(pose(), 4.0), -2 * yaw), FPS)
    turn = [f for f in a.findings if f.label == "turn"]
    assert len(turn) == 1 and turn[0].side == "right" and "turns around" in a.sentence()


def test_a_jump_up_and_a_stand_without_one():
    p = hold(pose(), 3.0).copy()
    t = np.arange(len(p)) / FPS
    flight = (t > 1.0) & (t < 1.45)
    p[flight, :, 1] += (4.8 * (t[flight] - 1.0) * (1.45 - t[flight]))[:, None]  # 0.24 m
    jumps = [f for f in analyse_positions(p, FPS).findings if f.label == "jump"]
    assert len(jumps) == 1 and jumps[0].detail["direction"] == "up"
    assert "jump" not in labels(hold(pose(), 3.0))
    # a flight falls as thrown bodies fall; a body held up (a bar, a frame, its toes) does not
    body = Body.from_positions(p, FPS)
    a, b = int(1.05 * body.fps), int(1.4 * body.fps)
    assert ballistic(body, a, b)
    held = hold(pose(), 3.0).copy()
    held[flight, :, 1] += 0.24
    assert not ballistic(Body.from_positions(held, FPS), a, b)
    assert ballistic(body, a, a + 3)   # too short a span to tell: not ruled out


def test_balancing_on_one_leg_and_not_for_a_step():
    lifted = pose(LK=(0.09, 0.7, 0.3), LA=(0.09, 0.35, 0.25), LMrot=(0.09, 0.3, 0.2),
                  LF=(0.09, 0.28, 0.37))
    p = take(hold(pose(), 0.5), blend(pose(), lifted, 0.3), hold(lifted, 2.0),
             blend(lifted, pose(), 0.3), hold(pose(), 0.5))
    one = [f for f in analyse_positions(p, FPS).findings if f.label == "one_leg"]
    assert one and one[0].side == "right"   # standing on the right, the left raised
    short = take(hold(pose(), 0.5), blend(pose(), lifted, 0.2), blend(lifted, pose(), 0.2),
                 hold(pose(), 1.0))
    assert "one_leg" not in labels(short)


def test_hanging_by_the_hands():
    hangs = pose(LE=(0.2, 1.75, 0), LW=(0.2, 2.0, 0), RE=(-0.2, 1.75, 0), RW=(-0.2, 2.0, 0))
    up = hangs + np.array([0, 0.5, 0])
    p = take(hold(pose(), 1.0), blend(pose(), hangs, 0.5), blend(hangs, up, 1.0), hold(up, 2.0))
    a = analyse_positions(p, FPS)
    assert {"hang", "climb"} & {f.label for f in a.findings}
    assert a.main_action() == "climb"


def _ladder(rungs: int = 4, rise: float = 0.3, step: float = 0.4) -> np.ndarray:
    """Up a ladder: one foot onto the next rung, then the other with the body, the hands
    on the rungs above the head."""
    parts, cur = [hold(pose(), 1.0)], pose()
    for _ in range(rungs):
        for foot in (("LA", "LF", "LMrot", "LK"), ("RA", "RF", "RMrot", "RK")):
            nxt = cur.copy()
            moved = foot if foot[0] == "LA" else [n for n in I if n not in
                                                  ("LA", "LF", "LMrot", "LK")]
            for n in moved:
                nxt[I[n], 1] += rise
            for w, e, s in (("LW", "LE", "LS"), ("RW", "RE", "RS")):
                nxt[I[e]] = nxt[I[s]] + np.array([0, 0.28, 0.05])
                nxt[I[w]] = nxt[I[s]] + np.array([0, 0.55, 0.1])
            parts.append(blend(cur, nxt, step))
            cur = nxt
    return take(*parts, hold(cur, 1.5))


def test_climbing_a_ladder_up_and_down():
    up = analyse_positions(_ladder(), FPS)
    assert up.main_action() == "climb" and "climbs up" in up.sentence()
    down = analyse_positions(_ladder()[::-1].copy(), FPS)
    assert down.main_action() == "climb" and "climbs down" in down.sentence()
    # one step up onto a kerb is a step, not a climb
    kerb = labels(_ladder(rungs=1, rise=0.2))
    assert "step_up" in kerb and "climb" not in kerb


def _monkey_bars(seconds: float = 4.0, distance: float = 2.0, lift: float = 0.35) -> np.ndarray:
    """Hands up on a bar, pulled up off the floor, hand over hand along the bars (each hand
    holds still while the other reaches ahead) while the body swings under the grip (the
    legs most), then let go: a short fall onto the feet."""
    up = pose()
    for w, e, s in (("LW", "LE", "LS"), ("RW", "RE", "RS")):
        up[I[e]] = up[I[s]] + np.array([0, 0.3, 0])
        up[I[w]] = up[I[s]] + np.array([0, 0.6, 0])
    hung = up + np.array([0, lift, 0])
    t = np.arange(int(seconds * FPS)) / FPS
    along = np.repeat(hung[None], len(t), axis=0)
    body = distance * t / seconds
    along[:, :, 2] += body[:, None]
    v, period = distance / seconds, 0.8   # m/s; s between two moves of one hand
    for k, (w, e) in enumerate((("LW", "LE"), ("RW", "RE"))):
        # each hand still on a bar half the time, then moved on by the body's way in a
        # period (the two in turn): the place it grips, metres along the bars
        u = t / period - k / 2
        grip = v * period * (np.floor(u) + np.clip(2 * (u % 1.0), 0.0, 1.0))
        along[:, I[w], 2] += grip - body + 0.1
        along[:, I[e], 2] += (grip - body) / 2
    swing = np.sin(2 * np.pi * t / 1.2)
    legs = [I[n] for n in ("LK", "LA", "LMrot", "LF", "RK", "RA", "RMrot", "RF")]
    along[:, legs, 2] += (0.25 * swing)[:, None]
    along[:, [I[n] for n in ("root", "BP", "BT", "LH", "RH")], 2] += (0.1 * swing)[:, None]
    tf = np.arange(int(np.sqrt(2 * lift / 9.81) * FPS) + 1) / FPS
    fall = np.repeat(along[-1][None], len(tf), axis=0)
    fall[:, :, 1] -= (4.905 * tf ** 2)[:, None]
    end = pose() + np.array([0, 0, along[-1, 0, 2]])
    return take(hold(pose(), 1.0), blend(pose(), up, 0.5), blend(up, hung, 0.5), along, fall,
                blend(fall[-1], end, 0.5), hold(end, 1.0))


def test_hand_over_hand_along_a_bar_is_no_walk():
    """The swinging legs of a body hanging from a bar are neither a floor nor steps: the
    floor stays under them, and nothing walks."""
    a = analyse_positions(_monkey_bars(), FPS)
    found = {f.label for f in a.findings}
    assert "walk" not in found and "run" not in found and "step_up" not in found
    hang = [f for f in a.findings if f.label == "hang"]
    assert len(hang) == 1 and hang[0].value > 0.3 and hang[0].detail["travelled"]
    assert a.main_action() == "climb"
    assert a.sentence() == "a person hangs by the hands, moving along"
    # hanging still from the bar moves nowhere along it
    still = analyse_positions(_monkey_bars(distance=0.0), FPS)
    assert [f.detail["travelled"] for f in still.findings if f.label == "hang"] == [False]


@pytest.mark.parametrize("kind, slope", [("run", 0.04), ("run", 0.08), ("walk", 0.08)])
def test_arms_raised_on_a_slope_keep_the_floor_and_the_steps(kind, slope):
    """Hands overhead that grip nothing (a run with raised arms, up a ramp) leave the floor
    to the feet: the same contacts and steps as with the arms down, and no hang."""
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    from motionlang.features.joint_map import positions21
    rng = np.random.default_rng(4)
    motion, _, _ = build_motion([Primitive(kind, count=12, direction="forward")],
                                random_style(rng), rng)
    down = positions21(motion).copy()
    down[:, :, 1] += slope * (down[:, :, 2] - down[:, :, 2].min())
    up = down.copy()
    for w, e, s in (("LW", "LE", "LS"), ("RW", "RE", "RS")):
        up[:, I[e]] = up[:, I[s]] + np.array([0, 0.3, 0])
        up[:, I[w]] = up[:, I[s]] + np.array([0, 0.6, 0])
    got = []
    for p in (down, up):
        body = Body.from_positions(p, motion.fps)
        a = analyse_positions(p, motion.fps)
        got.append((round(float(body.contacts.any(axis=0).mean()), 2),
                    [f.detail["steps"] for f in a.findings if f.label == kind]))
        assert "hang" not in {f.label for f in a.findings}
    assert got[0] == got[1] and got[0][1]


def test_a_leap_with_the_hands_overhead_is_no_hang():
    """Feet off the floor under hands held high is a hang only where the body does not fall
    as thrown bodies do: a 0.7 s flight (0.6 m high) with the arms up is a jump."""
    up = pose()
    for w, e, s in (("LW", "LE", "LS"), ("RW", "RE", "RS")):
        up[I[e]] = up[I[s]] + np.array([0, 0.3, 0])
        up[I[w]] = up[I[s]] + np.array([0, 0.6, 0])
    p = take(hold(pose(), 1.0), blend(pose(), up, 0.3), hold(up, 2.5))
    t = np.arange(len(p)) / FPS
    flight = (t > 1.8) & (t < 2.5)
    p[flight, :, 1] += (4.905 * (t[flight] - 1.8) * (2.5 - t[flight]))[:, None]
    found = {f.label for f in analyse_positions(p, FPS).findings}
    assert "jump" in found and "hang" not in found


def test_walking_with_the_hands_overhead_walks_on_its_floor():
    """Hands overhead do not make a walk a hang: the feet still stand on the floor."""
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    from motionlang.features.joint_map import positions21
    rng = np.random.default_rng(4)
    motion, _, _ = build_motion([Primitive("walk", count=8, direction="forward")],
                                random_style(rng), rng)
    p = positions21(motion).copy()
    for w, e, s in (("LW", "LE", "LS"), ("RW", "RE", "RS")):
        p[:, I[e]] = p[:, I[s]] + np.array([0, 0.3, 0])
        p[:, I[w]] = p[:, I[s]] + np.array([0, 0.6, 0])
    body = Body.from_positions(p, motion.fps)
    assert body.hands_overhead.mean() > 0.9
    assert np.abs(body.local_floor - Body.from_positions(positions21(motion),
                                                         motion.fps).local_floor).max() < 0.02
    a = analyse_positions(p, motion.fps)
    assert a.main_action() == "walk" and "hang" not in {f.label for f in a.findings}


def _drop(height: float, seconds_on_top: float = 1.0) -> np.ndarray:
    """Standing on a box ``height`` m high, then a jump off it: a thrown body's fall
    (0.5 m/s up, 1 m/s forward) onto the floor, and standing there."""
    v0 = 0.5
    fall = (v0 + np.sqrt(v0 ** 2 + 2 * 9.81 * height)) / 9.81
    t = np.arange(int(fall * FPS)) / FPS
    flight = np.repeat(pose()[None], len(t), axis=0)
    flight[:, :, 1] += (height + v0 * t - 4.905 * t ** 2)[:, None]
    flight[:, :, 2] += t[:, None]
    landed = pose() + np.array([0, 0, fall])
    return take(hold(pose() + np.array([0, height, 0]), seconds_on_top), flight,
                hold(landed, 1.5))


@pytest.mark.parametrize("height", [0.3, 0.6, 1.0])
def test_a_jump_down_from_a_box_starts_where_the_feet_leave_it(height):
    a = analyse_positions(_drop(height), FPS)
    jumps = [f for f in a.findings if f.label == "jump"]
    assert len(jumps) == 1 and jumps[0].detail["direction"] == "down"
    # the flight begins when the feet leave the box (1.0 s), not when the floor's window
    # first reaches the floor below
    assert jumps[0].start == pytest.approx(1.0, abs=0.1)
    assert a.sentence() == "a person jumps down"   # no "steps down" beside it
    # stepping down without a flight is no jump
    body = take(hold(pose() + np.array([0, height, 0]), 1.0),
                blend(pose() + np.array([0, height, 0]), pose(), 0.8), hold(pose(), 1.5))
    assert "jump" not in labels(body)


def test_walking_from_the_procedural_generator():
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    rng = np.random.default_rng(4)
    style = random_style(rng)
    motion, _, _ = build_motion([Primitive("walk", count=8, direction="forward")], style, rng)
    a = analyse(motion)
    assert a.main_action() == "walk"
    walk = [f for f in a.findings if f.label == "walk"]
    assert walk[0].detail["direction"] == "forward"
    motion, _, _ = build_motion([Primitive("walk", count=8, direction="backward")], style, rng)
    assert [f.detail["direction"] for f in analyse(motion).findings
            if f.label == "walk"] == ["backwards"]


def test_thresholds_are_in_body_units():
    """The same motion in centimetres, at another frame rate, gives the same findings."""
    p = _punches(2, 0.12)
    a = analyse_positions(p, FPS)
    fast = np.repeat(p, 4, axis=0)   # the same motion sampled at 120 Hz
    b = analyse_positions(fast * 100.0, 4 * FPS)
    assert [(f.label, f.side, f.count) for f in a.findings] == \
        [(f.label, f.side, f.count) for f in b.findings]


@pytest.mark.parametrize("bad, why", [
    (np.zeros((1, 21, 3)), "1 frame"),
    (np.zeros((10, 21, 3)), "no length"),
    (np.zeros((10, 20, 3)), "(T, 21, 3)"),
    (np.full((10, 21, 3), np.nan), "finite"),
])
def test_degenerate_motion_is_one_clear_error(bad, why):
    with pytest.raises(MotionlangError) as e:
        analyse_positions(bad, FPS)
    assert why.split()[-1] in str(e.value)


def test_absurd_speeds_give_a_sentence_not_a_traceback():
    p = hold(pose(), 2.0).copy()
    p += np.arange(len(p))[:, None, None] * np.array([100.0, 0, 0])   # 3 km/s
    text = analyse_positions(p, FPS).sentence()
    assert isinstance(text, str) and text


def test_nothing_found_is_said_as_such():
    jitter = np.random.default_rng(1).normal(0, 0.3, (60, 21, 3)) + pose()
    a = analyse_positions(jitter, FPS)
    assert a.sentence() == CANNOT_TELL or a.findings


def test_confidence_and_masks():
    assert confidence(1.0, 1.0, 0.5) == 0.5
    assert confidence(1.5, 1.0, 0.5) == 1.0 and confidence(0.0, 1.0, 0.5) == 0.0
    assert confidence(0.2, 0.5, -0.3) == 1.0           # below a threshold
    assert confidence(2.0, 1.0, 0.5, duration=0.25, full_after=1.0) == pytest.approx(0.5)
    m = np.array([0, 1, 1, 0, 1, 1, 1, 0, 0, 0, 1], bool)
    assert runs(m) == [(1, 3), (4, 7), (10, 11)]
    cleaned = clean_mask(m, 10.0, min_len=0.3, max_gap=0.1)
    assert runs(cleaned) == [(1, 7)]


def test_sentences_never_repeat_themselves():
    assert tidy("a person takes 6 steps 6 steps 6 steps forward") == \
        "a person takes 6 steps forward"
    assert tidy("lumbering street punk punk") == "lumbering street punk"
    assert repeats("squatting squats squats") and not repeats("a person walks forward")
    # two counts side by side (cmu_dev iclone/05_07's first sentence): the second reworded
    said = join(["kicks with the left leg twice", "spins around twice", "walks forward"])
    assert said == ("a person kicks with the left leg twice, spins around two times, then "
                    "walks forward") and not repeats(said)


def test_actions_named_in_words():
    assert actions_named("A man jogs forward, then sits down") == ["run", "sit"]
    assert actions_named("someone strolls along") == ["walk"]
    assert actions_named("someone does the tango") == []   # words the table lacks
    assert agrees(["crouch"], "bend") and not agrees(["walk"], "punch")


def test_mentions_read_each_actions_side_direction_negation_and_order():
    from motionlang.analysis.words import mentions
    got = mentions("A man kicks twice with the left leg, then walks backwards without running")
    assert [(m.action, m.side, m.direction, m.negated, m.after_previous) for m in got] == [
        ("kick", "left", None, False, False), ("walk", None, "backwards", False, True),
        ("run", None, None, True, False)]
    assert [m.side for m in mentions("a person balances on the right leg")] == ["right"]
    assert not mentions("someone never stops walking")[0].negated   # "never" is the stop's
    assert mentions("the person is not jumping")[0].negated
    assert [m.after_previous for m in mentions("walks twice before jumping")] == [False, True]


def test_check_says_yes_no_and_cannot_tell():
    from motionlang.analysis.check import check_sentence
    p = take(hold(pose(), 1.0), blend(pose(), SIT, 1.0), hold(SIT, 2.0))
    got = check_sentence("a person sits down, then punches and throws", analyse_positions(p, FPS))
    assert [(c.action, c.shown) for c in got] == [("sit", True), ("punch", False),
                                                 ("throw", None)]
    assert got[0].findings[0].label == "sit" and got[0].line().startswith("sit: yes (")
    assert got[1].line() == "punch: no" and "cannot tell" in got[2].line()


def _seen(*findings: tuple) -> Analysis:
    """An analysis of the findings ``(label, start, end, side, detail)``."""
    return Analysis(findings=tuple(
        Finding("test", lab, a, b, "measure", 1.0, 0.5, 0.9, side=side, detail=detail or {})
        for lab, a, b, side, detail in findings), duration=10.0, leg=0.9, stature=1.75)


def test_check_reads_the_side_the_direction_the_order_and_a_no():
    from motionlang.analysis.check import check_sentence
    a = _seen(("walk", 0.0, 3.0, None, {"direction": "forward", "path": "straight"}),
              ("kick", 3.0, 4.0, "right", None), ("turn", 4.0, 5.0, "left", None),
              ("jump", 5.0, 5.5, None, {"direction": "up"}),
              ("raise", 6.0, 8.0, "right", None))

    def said(text):
        return [(c.action, c.shown, c.met) for c in check_sentence(text, a)]

    assert said("a person kicks with the right leg") == [("kick", True, True)]
    got = check_sentence("a person kicks with the left leg", a)
    assert (got[0].shown, got[0].line()) == (False, "kick: no (seen on the right side, "
                                                    "3.0-4.0 s)")
    assert said("a person turns left") == [("turn", True, True)]
    assert said("a person turns right") == [("turn", False, False)]
    assert said("a person walks backwards") == [("walk", False, False)]
    assert said("a person walks forward and then jumps up") == [("walk", True, True),
                                                               ("jump", True, True)]
    got = check_sentence("a person jumps, then walks forward", a)
    assert [(c.action, c.shown) for c in got] == [("jump", True), ("walk", False)]
    assert got[1].note == "only before the jump, 0.0-3.0 s"
    assert said("a person raises both hands") == [("raise", False, False)]
    # "then" of things done together: a turn while walking, a wave within the raise
    during = _seen(("walk", 0.0, 3.0, None, {"direction": "forward", "path": "straight"}),
                   ("turn", 1.0, 2.0, "left", None), ("raise", 4.0, 7.0, "right", None),
                   ("wave", 5.0, 6.0, "right", None))
    assert [c.met for c in check_sentence("a person walks forward, then turns left", during)
            ] == [True, True]
    assert [c.met for c in check_sentence("a person raises the right hand, then waves",
                                          during)] == [True, True]
    # "not": its own findings only (a raised hand is no wave)
    assert said("a person raises the right hand and does not wave") == [
        ("raise", True, True), ("wave", False, True)]
    assert said("a person walks back and forth") == [("walk", True, True)]
    assert said("a person raises the right hand") == [("raise", True, True)]
    # what the sentence says the body does not do
    assert said("a person does not sit") == [("sit", False, True)]
    got = check_sentence("a person doesn't jump", a)
    assert (got[0].shown, got[0].met) == (True, False) and got[0].line().startswith(
        "jump (the sentence says not): yes (")


def test_a_span_holding_part_of_a_series_counts_its_share():
    spins = Analysis(findings=(Finding("turn", "spin", 0.0, 4.4, "facing turned (deg)", 1080.0,
                                       45.0, 1.0, side="left", count=3,
                                       detail={"angle": 1080.0, "rounded": 1080}),),
                     duration=4.4, leg=0.9, stature=1.75)
    assert [f.count for f in spins.within(0.0, 4.4).findings] == [3]
    assert [f.count for f in spins.within(3.4, 4.4).findings] == [1]   # a quarter of it
    assert [f.count for f in spins.within(0.0, 3.0).findings] == [2]


def test_the_open_world_check_as_a_share():
    from motionlang.evaluation.open_world import check_share, shown
    sat = take(hold(pose(), 1.0), blend(pose(), SIT, 1.0), hold(SIT, 2.0))
    stood = hold(pose(), 4.0)
    assert shown("a person sits down", sat, FPS) is True
    assert shown("a person sits down", stood, FPS) is False
    assert shown("a person throws a ball", sat, FPS) is None   # nothing it can tell
    assert shown("a person sits", sat[:1], FPS) is None         # one frame: unread
    assert check_share(["a person sits down", "a person sits down", "a person throws"],
                       [sat, stood, sat], FPS) == 0.5
    assert np.isnan(check_share(["someone throws"], [sat], FPS))
    with pytest.raises(MotionlangError):
        check_share(["a"], [], FPS)


@pytest.mark.parametrize("fps", [1e-12, 1e-3, 1e6])
def test_an_absurd_frame_rate_is_a_sentence_not_a_traceback(fps):
    """A header that claims 1e12 s a frame (or a millionth of a second) must neither fill
    the memory with a timeline nor break the filters."""
    a = analyse_positions(hold(pose(), 3.0), fps)
    assert a.duration == pytest.approx(90 / fps)
    assert a.sentence() and len(a.timeline()) >= 1


def test_findings_close_in_time_are_one_series_with_their_count():
    from motionlang.analysis.evidence import Finding, merge_series

    def bow(t0, t1, c=0.8):
        return Finding("limb", "bow", t0, t1, "tilt", 40.0, 25.0, c)
    got = merge_series([bow(5.0, 5.5), bow(0.0, 0.5, 0.9), bow(1.0, 1.5), bow(9.0, 9.5)])
    assert [(f.start, f.end, f.count) for f in got] == [(0.0, 1.5, 2), (5.0, 5.5, 1),
                                                        (9.0, 9.5, 1)]
    assert got[0].confidence == 0.9
    assert merge_series([bow(0, 1), bow(1.2, 2)], label="squat")[0].label == "squat"


def test_a_splice_is_found_and_a_smooth_take_has_none():
    """Two recordings end to end (the second on a floor 0.15 m lower, in another pose) are
    two pieces cut at the splice; a jump, a fast punch and a one-frame glitch in a short
    stretch are not splices."""
    jump = hold(pose(), 3.0).copy()
    t = np.arange(len(jump)) / FPS
    flight = (t > 1.0) & (t < 1.45)
    jump[flight, :, 1] += (4.8 * (t[flight] - 1.0) * (1.45 - t[flight]))[:, None]
    assert pieces(jump, FPS) == [(0, len(jump))]
    assert pieces(_punches(3, 0.12), FPS) == [(0, len(_punches(3, 0.12)))]
    lower = hold(pose(LW=(0.2, 1.6, 0.1), RW=(-0.2, 1.6, 0.1)), 2.0) - np.array([0, 0.15, 0])
    spliced = take(jump, lower)
    assert pieces(spliced, FPS) == [(0, len(jump)), (len(jump), len(spliced))]
    glitch = spliced.copy()
    glitch[len(jump) + 10] += 0.3   # one frame off its path and back
    assert [a for a, _ in pieces(glitch, FPS)] == [0, len(jump)]


def test_a_spliced_take_is_read_piece_by_piece_on_its_own_floor():
    """A stand on a floor 0.15 m higher, then the jump take: the raised feet are no flight,
    and the jump is found where it happens in the take."""
    p = hold(pose(), 3.0).copy()
    t = np.arange(len(p)) / FPS
    flight = (t > 1.0) & (t < 1.45)
    p[flight, :, 1] += (4.8 * (t[flight] - 1.0) * (1.45 - t[flight]))[:, None]
    raised = hold(pose(LW=(0.2, 1.6, 0.1), RW=(-0.2, 1.6, 0.1)), 2.0) + np.array([0, 0.15, 0])
    jumps = [f for f in analyse_positions(take(raised, p), FPS).findings if f.label == "jump"]
    assert len(jumps) == 1 and 2.9 < jumps[0].start < 3.1


def _finding(label: str, start: float, end: float) -> Finding:
    return Finding("locomotion", label, start, end, "test", 1.0, 0.5, 1.0,
                   detail={"direction": "forward"})


def test_a_pause_beside_a_jump_is_the_jumps_and_a_walk_ends_where_it_ends():
    walk_then_jump = Analysis((_finding("walk", 0.0, 4.0), _finding("jump", 5.1, 5.5)),
                              duration=6.5, leg=0.84, stature=1.7)
    assert [a for a, _, _ in walk_then_jump.timeline()] == [0.0, 4.0]
    # between two travels a short pause goes to the longer one, as before
    walk_then_run = Analysis((_finding("walk", 0.0, 4.0), _finding("run", 4.5, 7.0)),
                             duration=7.0, leg=0.84, stature=1.7)
    assert [a for a, _, _ in walk_then_run.timeline()] == [0.0, 4.5]
    # a pause longer than GAP_REACH stays a part of its own
    long_pause = Analysis((_finding("walk", 0.0, 4.0), _finding("jump", 6.0, 6.4)),
                          duration=7.0, leg=0.84, stature=1.7)
    assert [a for a, _, _ in long_pause.timeline()] == [0.0, 4.0, 5.4]


@pytest.mark.parametrize("text, want", [
    ("a person puts the left hand up high", [("raise", "left")]),
    ("someone throwing both hands up over their head", [("raise", "both")]),
    ("somebody reaches skyward with the right arm", [("raise", "right")]),
    ("a person signals goodbye using only the right arm", [("wave", "right")]),
    ("someone greets with both palms", [("wave", "both")]),
    ("shakes the left hand from side to side", [("wave", "left")]),
    ("ambles ahead and then bears to the left", [("walk", None), ("turn", "left")]),
    ("heading forward on foot, then taking a right", [("walk", None), ("turn", "right")]),
    ("goes round the corner", [("turn", None)]),
    ("a person racing ahead", [("run", None)]),
    ("throws a punch", [("punch", None)]),
    ("bends to the left", [("bend", "left")]),   # a bend of the trunk, not a turn
    ("throws a ball", [("throw", None)]),
])
def test_actions_named_in_other_words(text, want):
    from motionlang.analysis.words import mentions
    assert [(m.action, m.side) for m in mentions(text)] == want


@pytest.mark.parametrize("text, want", [
    ("walks forward swinging the arms back and forth", ["walk"]),   # a walk's arm swing
    ("takes a left step forward", ["walk"]),
    ("makes a right angle with both arms", []),
    ("curves his left arm", []),
    ("brings the left hand up to his mouth", []),
    ("brings both arms up and down repeatedly", []),
    ("walks forward in a hurry", ["walk"]),
    ("stands on tiptoes", ["stand"]),
    ("hikes his shoulders", []),
    ("greets a friend with a bow", ["bow"]),
    ("bows in greeting", ["bow"]),
    ("puts the flag down", []),
    ("reaches up to a shelf", ["reach"]),
    ("walks a 90 degree curve to the left", ["walk"]),
])
def test_other_words_name_no_action_the_sentence_does_not(text, want):
    assert actions_named(text) == want


def test_before_that_looks_back():
    from motionlang.analysis.words import mentions
    got = mentions("a person walks forward, but before that he waves")
    assert [(m.action, m.after_previous) for m in got] == [("walk", False), ("wave", False)]


def test_a_walk_with_its_travel_taken_out_walks_in_place():
    """On a treadmill (or a take whose root's travel was removed, as the MIT walking data)
    the feet stride past each other while the root stays: a walk in place, no "stands
    still", and no walk forward for check."""
    from motionlang.analysis import check_sentence
    from motionlang.analysis.locomotion import striding
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    from motionlang.features.joint_map import positions21
    rng = np.random.default_rng(4)
    motion, _, _ = build_motion([Primitive("walk", count=10, direction="forward")],
                                random_style(rng), rng)
    p = positions21(motion).copy()
    p[:, :, [0, 2]] -= p[:, :1, [0, 2]]   # the root held at the origin, the body facing on
    for fps in (motion.fps, motion.fps / 2):   # half speed: feet slow enough to read as down
        body = Body.from_positions(p, fps)
        assert float(body.ground_speed.max()) < 0.3          # no travel left to see
        assert striding(body).mean() > 0.5   # all but the start and the end (0.65-0.79)
        a = analyse_positions(p, fps)
        walks = [f for f in a.findings if f.label == "walk"]
        assert len(walks) == 1 and walks[0].detail["in_place"] and walks[0].duration > 4
        assert 6 <= walks[0].detail["steps"] <= 12   # 10 steps, the first and last short
        assert "stand" not in [f.label for f in a.findings]
        assert a.sentence() == "a person walks in place"
        forward, = check_sentence("a person walks forward", a)
        assert not forward.shown and "in place" in forward.note
        assert check_sentence("a person walks", a)[0].shown
    still = np.repeat(p[:1], len(p), axis=0)               # the same body, not moving
    assert not striding(Body.from_positions(still, motion.fps)).any()
    assert labels(still, motion.fps) == ["stand"]


def test_side_steps_with_their_travel_taken_out_do_not_stand_still():
    """Feet that step, each raised in turn, are no standing body even where they do not
    stride past each other (side steps held in place): the analysis cannot tell, rather
    than "stands still"."""
    from motionlang.analysis.locomotion import stepping
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    from motionlang.features.joint_map import positions21
    rng = np.random.default_rng(4)
    motion, _, _ = build_motion([Primitive("walk", count=8, direction="left")],
                                random_style(rng), rng)
    p = positions21(motion).copy()
    p[:, :, [0, 2]] -= p[:, :1, [0, 2]]
    assert stepping(Body.from_positions(p, motion.fps)).mean() > 0.5
    assert "stand" not in labels(p, motion.fps)
    still = np.repeat(p[:1], len(p), axis=0)
    assert not stepping(Body.from_positions(still, motion.fps)).any()


@pytest.mark.parametrize("seed", [4, 5])
def test_a_run_with_its_travel_taken_out_runs_in_place(seed):
    """In place the root's speed says nothing of the gait: the flights of the lower foot
    and the cadence do."""
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    from motionlang.features.joint_map import positions21
    rng = np.random.default_rng(seed)
    motion, _, _ = build_motion([Primitive("run", count=12, direction="forward")],
                                random_style(rng), rng)
    p = positions21(motion).copy()
    p[:, :, [0, 2]] -= p[:, :1, [0, 2]]
    assert analyse_positions(p, motion.fps).sentence() == "a person runs in place"


def test_nobody_negates_and_in_place_is_a_way_of_walking():
    from motionlang.analysis.words import mentions
    assert mentions("nobody walks")[0].negated and mentions("no one waves")[0].negated
    assert mentions("a person walks in place")[0].direction == "in place"
    assert mentions("jogs on the spot")[0].direction == "in place"
    assert actions_named("a person gets up") == ["stand"]
    assert actions_named("someone sidesteps to the left") == ["walk"]


def test_broken_openings_are_garbled():
    from motionlang.analysis.sentences import garbled
    assert garbled("an is walking forward") and garbled("both person raises both hands")
    assert not garbled("a person is walking forward") and not garbled("a person raises both hands")


def test_check_asks_a_walks_path_and_pace():
    """"walks in a circle" is no on a straight walk; "walks quickly" no on a slow one and
    "slowly" no on a brisk one (by the Froude number), each with how it was seen."""
    from motionlang.analysis import check_sentence
    from motionlang.analysis.words import mentions
    from motionlang.datasets.synth import Primitive
    from motionlang.datasets.synth.compose import build_motion, random_style
    from motionlang.features.joint_map import positions21

    def walk(**kw):
        rng = np.random.default_rng(4)
        motion, _, _ = build_motion([Primitive("walk", **kw)], random_style(rng), rng)
        return analyse_positions(positions21(motion), motion.fps)

    assert [(m.path, m.pace) for m in mentions("a man slowly walks in a circle")] == [
        ("in a circle", "slow")]
    slow, brisk = (walk(count=8, direction="forward", speed=s) for s in ("slow", "fast"))
    circle = walk(count=16, direction="circle", side="left")
    asked = [check_sentence(t, a)[0] for t, a in (
        ("a person walks in a circle", slow), ("a person walks in a circle", circle),
        ("a person walks quickly", slow), ("a person walks slowly", slow),
        ("a person walks slowly", brisk), ("a person walks briskly", brisk))]
    assert [c.shown for c in asked] == [False, True, False, True, False, True]
    assert "slower than most walks" in asked[2].note and "briskly" in asked[4].note

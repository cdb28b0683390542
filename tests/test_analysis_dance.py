"""The dance detector (``analysis.dance``): a mix of leg and arm movements on a body the test
builds is a dance, and the same movements with a punch, on a body held still, or too few or
too short, are not."""
from __future__ import annotations

import numpy as np

from helpers.bodies import FPS, I, blend, hold, pose, take, turned
from motionlang.analysis import analyse_positions
from motionlang.analysis.body import Body
from motionlang.analysis.check import check_sentence
from motionlang.analysis.dance import MIN_DANCE, dances, said_by_dance
from motionlang.analysis.evidence import Finding
from motionlang.analysis.words import actions_named

UP = pose(LE=(0.2, 1.7, 0), LW=(0.2, 1.95, 0), RE=(-0.2, 1.7, 0), RW=(-0.2, 1.95, 0))
#: a straight leg swung forward to hip height
KICK_L = pose(LK=(0.09, 0.95, 0.42), LA=(0.09, 0.98, 0.83), LMrot=(0.09, 0.98, 0.78),
              LF=(0.09, 1.0, 0.95))
KICK_R = pose(RK=(-0.09, 0.95, 0.42), RA=(-0.09, 0.98, 0.83), RMrot=(-0.09, 0.98, 0.78),
              RF=(-0.09, 1.0, 0.95))
GUARD = pose(RE=(-0.22, 1.2, 0.15), RW=(-0.2, 1.38, 0.18))
JAB = pose(RE=(-0.18, 1.42, 0.28), RW=(-0.18, 1.42, 0.54))


def _dance(middle: list[np.ndarray] | None = None) -> np.ndarray:
    """Arms raised, a left kick, a spin on the spot (``middle`` instead), a right kick, arms
    raised again, the hands swaying all the while: 4.8 s."""
    base = pose()
    spin = hold(base, 1.0)
    spin = turned(spin, np.linspace(0, 2 * np.pi, len(spin)))
    parts = [hold(base, 0.3), blend(base, UP, 0.4), hold(UP, 0.4), blend(UP, base, 0.4),
             blend(base, KICK_L, 0.2), blend(KICK_L, base, 0.3), *(middle or [spin]),
             blend(base, KICK_R, 0.2), blend(KICK_R, base, 0.3),
             blend(base, UP, 0.4), hold(UP, 0.5), blend(UP, base, 0.4)]
    p = take(*parts)
    t = np.arange(len(p)) / FPS
    for j in ("LW", "RW"):
        p[:, I[j], 0] += 0.15 * np.sin(2 * np.pi * 1.5 * t)
    return p


def test_kicks_spins_and_raised_arms_in_a_row_are_a_dance():
    a = analyse_positions(_dance(), FPS)
    assert a.main_action() == "dance"
    assert a.sentence() == "a person dances"
    assert a.sentence("detailed") == "a person dances (kicks, raised arms, spins)"
    (text, f), = a.explain()
    assert f.label == "dance" and f.value >= 3 and "different movements" in f.measure
    # the movements it is made of are said by it, and a check of them still finds them
    assert not {"kick", "spin", "raise"} & {g.label for g in a.findings}
    shown = {c.action: c.shown for c in check_sentence("a person dances and kicks", a)}
    assert shown == {"dance": True, "kick": True}
    assert [c.shown for c in check_sentence("a person sits down", a)] == [False]


def test_the_same_kicks_with_a_punch_are_fighting_not_a_dance():
    punch = [blend(GUARD, JAB, 0.12), blend(JAB, GUARD, 0.3), hold(pose(), 0.5)]
    a = analyse_positions(_dance(middle=punch), FPS)
    labels = {f.label for f in a.findings}
    assert "dance" not in labels and {"kick", "punch"} <= labels
    assert "dances" not in a.sentence()


def _f(label: str, start: float, end: float) -> Finding:
    return Finding("limb", label, start, end, "test", 1.0, 0.5, 1.0)


def _body(seconds: float, moving: bool) -> Body:
    p = hold(pose(), seconds)
    if moving:
        t = np.arange(len(p)) / FPS
        p[:, I["RW"], 0] += 0.15 * np.sin(2 * np.pi * 1.5 * t)
    return Body.from_positions(p, FPS)


MIX = [_f("raise", 0.2, 1.0), _f("kick", 1.2, 1.6), _f("spin", 2.0, 3.0), _f("kick", 3.2, 3.6),
       _f("raise", 3.8, 4.6)]


def test_dances_needs_legs_arms_three_kinds_moving_limbs_and_time():
    danced = dances(_body(5.0, moving=True), MIX)
    assert len(danced) == 1 and danced[0].label == "dance"
    assert danced[0].detail["moves"] == ["kick", "raise", "spin"]
    # the same findings on a body whose limbs are still (a pose held for a photograph)
    assert dances(_body(5.0, moving=False), MIX) == []
    # arms only, legs only
    arms = [_f("raise", 0.2, 1.0), _f("wave", 1.5, 3.0), _f("clap", 3.2, 4.0)]
    assert dances(_body(5.0, moving=True), arms) == []
    legs = [_f("kick", 0.2, 0.6), _f("spin", 1.0, 2.0), _f("one_leg", 2.5, 4.0)]
    assert dances(_body(5.0, moving=True), legs) == []
    # a spin during a kick is the kick's turn: kick and raise are two kinds, not three
    spin_kick = [_f("raise", 0.2, 1.0), _f("spin", 1.1, 1.9), _f("kick", 1.3, 1.7),
                 _f("raise", 3.0, 4.0)]
    assert dances(_body(5.0, moving=True), spin_kick) == []
    # spinning kicks 4.5 s apart with the guard raised between (Bandai's kick take): a 4-s
    # window that holds one kick's spin but not its kick still holds no third kind
    kicks = [_f("spin", 0.2, 1.8), _f("kick", 0.9, 1.5), _f("raise", 2.5, 3.2),
             _f("spin", 4.7, 6.3), _f("kick", 5.4, 6.0), _f("raise", 7.0, 7.7),
             _f("spin", 9.2, 10.8), _f("kick", 9.9, 10.5)]
    assert dances(_body(11.0, moving=True), kicks) == []
    # too short a take
    short = [f for f in MIX if f.end <= MIN_DANCE - 0.5]
    assert dances(_body(MIN_DANCE - 0.5, moving=True), short) == []


def test_what_a_dance_says_is_dropped_and_the_rest_kept():
    dance = Finding("limb", "dance", 0.0, 5.0, "m", 3.0, 2.5, 0.75, detail={"moves": []})
    walk_after = Finding("locomotion", "walk", 5.0, 9.0, "m", 1.0, 0.5, 1.0)
    kept = said_by_dance([*MIX, dance, walk_after])
    assert [f.label for f in kept] == ["dance", "walk"]
    assert said_by_dance(MIX) == MIX


def test_dance_words():
    assert actions_named("a ballerina dances a pirouette") == ["dance", "spin"]

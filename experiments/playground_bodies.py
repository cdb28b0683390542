"""Playground bodies built joint by joint (no real take of one is here): hand over hand
along a bar, up a ladder with the hands in turn, a pull-up onto a 1 m ledge, and up a
ladder, sitting on the platform's edge with the legs hanging and jumping down, sitting on a
swing; what the
analysis says of each (main action, detailed sentence, the first findings).

    .venv/bin/python experiments/playground_bodies.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from helpers.bodies import FPS, SIT, STAND, I, blend, hold, pose, take  # noqa: E402
from motionlang.analysis import analyse_positions  # noqa: E402
from test_analysis import _monkey_bars  # noqa: E402

ARMS = (("LW", "LE", "LS"), ("RW", "RE", "RS"))
LEGJ = {"L": ("LA", "LF", "LMrot", "LK"), "R": ("RA", "RF", "RMrot", "RK")}

def hands_at(p, lz, rz, up=0.55):
    q = p.copy()
    for (w, e, s), z in zip(ARMS, (lz, rz)):
        q[I[e]] = q[I[s]] + np.array([0, up * 0.5, z * 0.5])
        q[I[w]] = q[I[s]] + np.array([0, up, z])
    return q

def ladder_alternating(rungs=4, rise=0.3, step=0.5):
    parts, cur = [hold(pose(), 1.0)], pose()
    k = 0
    for _ in range(rungs):
        for side in ("L", "R"):
            nxt = cur.copy()
            moved = LEGJ[side] if side == "L" else [n for n in I if n not in LEGJ["L"]]
            for n in moved:
                nxt[I[n], 1] += rise
            hi, lo = (0.55, 0.15) if k % 2 == 0 else (0.15, 0.55)
            nxt = hands_at(nxt, 0.25, 0.25, 0) 
            for (w, e, s), u in zip(ARMS, (hi, lo)):
                nxt[I[e]] = nxt[I[s]] + np.array([0, u * 0.5, 0.15])
                nxt[I[w]] = nxt[I[s]] + np.array([0, u, 0.3])
            parts.append(blend(cur, nxt, step))
            cur = nxt
            k += 1
    return take(*parts, hold(cur, 1.5)), cur

def mantle(h=1.0):
    p0 = pose()
    grab = p0.copy()
    for w, e, s in ARMS:
        grab[I[w]] = [grab[I[s]][0], h + 0.02, 0.35]
        grab[I[e]] = (grab[I[w]] + grab[I[s]]) / 2 + np.array([0, 0, -0.05])
    pulled = grab + np.array([0, h * 0.6, 0.1])
    for w, _, s in ARMS:
        pulled[I[w]] = [pulled[I[s]][0], h + 0.02, 0.35]
    top = pose() + np.array([0, h, 0.45])
    return take(hold(p0, 1.0), blend(p0, grab, 0.6), hold(grab, 0.3), blend(grab, pulled, 1.0),
                blend(pulled, top, 1.0), hold(top, 1.5))

def climb_sit_dangle_jump(h=0.9):
    lad, top = ladder_alternating(3, 0.3)
    stand_top = pose() + np.array([0, h, 0])
    # dangling sit on the edge: pelvis on the platform, legs hanging down below its edge
    dangle = SIT + np.array([0, h - 0.45, 0])
    for side in "LR":
        a, f, m, k = LEGJ[side]
        x = STAND[k][0]
        dangle[I[k]] = [x, h + 0.05, 0.42]
        dangle[I[a]] = [x, h - 0.35, 0.5]
        dangle[I[m]] = [x, h - 0.4, 0.45]
        dangle[I[f]] = [x, h - 0.42, 0.6]
    sw = hold(dangle, 3.0).copy()
    t = np.arange(len(sw)) / FPS
    for side, ph in (("L", 0), ("R", np.pi)):
        for n in LEGJ[side][:3]:
            sw[:, I[n], 2] += 0.1 * np.sin(2 * np.pi * t / 1.0 + ph)
    fall = np.sqrt(2 * h / 9.81)
    tf = np.arange(int(fall * FPS) + 1) / FPS
    fly = np.repeat(stand_top[None], len(tf), 0).copy()
    fly[:, :, 1] -= (4.905 * tf ** 2)[:, None]
    fly[:, :, 2] += (1.0 * tf)[:, None]
    land = pose() + np.array([0, 0, tf[-1]])
    return take(lad, blend(top, stand_top, 0.5), hold(stand_top, 0.5), blend(stand_top, dangle, 1.0), sw,
                blend(dangle, stand_top, 1.0), hold(stand_top, 0.5), fly, hold(land, 1.5))

def swing(seconds=8.0, amp=30.0, radius=2.0, period=2.8):
    seat = SIT.copy()
    # legs forward-down off the seat, feet off the floor
    for side in "LR":
        a, f, m, k = LEGJ[side]
        x = STAND[k][0]
        seat[I[k]] = [x, 0.5, 0.42]; seat[I[a]] = [x, 0.15, 0.6]; seat[I[m]] = [x, 0.1, 0.55]; seat[I[f]] = [x, 0.12, 0.72]
    for (w, e, s) in ARMS:
        seat[I[w]] = seat[I[s]] + [0, 0.1, 0.15]; seat[I[e]] = seat[I[s]] + [0, -0.15, 0.1]
    seat = seat + [0, 0.25, 0]
    pivot = np.array([0, 0.5 + 0.25 + radius, 0])
    t = np.arange(int(seconds * FPS)) / FPS
    th = np.radians(amp) * np.sin(2 * np.pi * t / period)
    rel = seat - pivot
    out = np.empty((len(t), 21, 3))
    for i, a in enumerate(th):
        c, s = np.cos(a), np.sin(a)
        y = rel[:, 1] * c - rel[:, 2] * s
        z = rel[:, 1] * s + rel[:, 2] * c
        out[i] = np.stack([rel[:, 0], y, z], 1) + pivot
    return out


def main() -> None:
    bodies = [("monkey bars", _monkey_bars()),
              ("ladder, hands alternating", ladder_alternating()[0]),
              ("mantle 1 m", mantle()),
              ("climb, sit, dangle legs, jump down", climb_sit_dangle_jump()),
              ("a swing, 30 degrees each way", swing())]
    for name, p in bodies:
        a = analyse_positions(p, FPS)
        print(f"## {name} ({len(p) / FPS:.1f} s): main {a.main_action()}")
        print("  ", a.sentence("detailed"))
        for f in a.ranked()[:8]:
            print(f"   {f.label:10s} {f.start:5.2f}-{f.end:5.2f} conf {f.confidence:.2f} "
                  f"{f.measure}={f.value:.2f}")


if __name__ == "__main__":
    main()

"""What the body does, from physics and geometry alone: posture and support, locomotion,
turns, changes of level and limb actions, each with its evidence, for any motion of any rig
(pure numpy/scipy on the 21-joint body; no model, no training).

    >>> from motionlang.analysis import analyse
    >>> a = analyse(motion)              # a Motion (any rig)
    >>> a.sentence()                     # "a person walks forward and then sits down"
    >>> a.timeline()                     # [(0.0, 4.2, "a person walks forward"), ...]
    >>> for text, finding in a.explain(): print(text, "<-", finding.evidence())
"""
from __future__ import annotations

from pathlib import Path

from motionlang.analysis.analyse import ACTION, VERSION, Analysis, analyse_positions, salience
from motionlang.analysis.body import Body
from motionlang.analysis.check import ActionCheck, check_sentence
from motionlang.analysis.evidence import Finding
from motionlang.analysis.sentences import CANNOT_TELL, garbled, repeats, tidy
from motionlang.features.joint_map import positions21
from motionlang.formats import read_motion
from motionlang.kinematics.motion import Motion

__all__ = ["ACTION", "CANNOT_TELL", "VERSION", "ActionCheck", "Analysis", "Body", "Finding", "analyse",
           "analyse_positions", "check", "garbled", "repeats", "salience", "tidy"]


def analyse(motion: Motion | str | Path, *,
            joint_map: dict | str | Path | None = None) -> Analysis:
    """A :class:`Motion` of any rig, or a motion file, -> its :class:`Analysis` (the body
    map of ``features.joint_map``, the one every command uses; ``joint_map`` for a rig no
    built-in map fits)."""
    if not isinstance(motion, Motion):
        motion = read_motion(motion, joint_map=joint_map)
    return analyse_positions(positions21(motion, joint_map=joint_map), motion.fps)


def check(text: str, motion: Motion | str | Path, *,
          joint_map: dict | str | Path | None = None) -> list[ActionCheck]:
    """Which actions of ``text`` a motion (a ``Motion`` or a file, any rig) shows, with
    evidence: an :class:`ActionCheck` per action the sentence names, in its order (``shown``
    True, False, or None where no detector can tell), as ``motionlang check`` prints them."""
    return check_sentence(text, analyse(motion, joint_map=joint_map))

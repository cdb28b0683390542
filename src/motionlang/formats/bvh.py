"""Biovision hierarchy (BVH): read files as they exist in the wild, write any Motion.

Conventions: Y up; a joint's rotation is the product of its rotation channels in file order
(``CHANNELS 3 Zrotation Xrotation Yrotation`` -> ``Rz @ Rx @ Ry``), which is exactly
``Skeleton``'s DOF chain with ``pre = post = I``; angles in degrees; each joint may have its
own channel order and position channels (on the root they add to its OFFSET, elsewhere they
replace it); ``End Site`` nodes (named or not) become DOF-free joints, named ``<parent>_end``
unless the file names them; the length unit is decided from the body
(:mod:`motionlang.formats.units`) unless given. Reading is in :mod:`.bvh_read` and
:mod:`.bvh_build`, writing in :mod:`.bvh_write`.

``Motion.meta`` of a BVH read (all lengths of ``bvh_hierarchy`` in file units):

* ``path``: the file read.
* ``frame_time``: the file's ``Frame Time`` in seconds, exactly (``fps`` is ``1 / frame_time``
  rounded to the nearest integer when within 0.2 %).
* ``unit``: ``"m"``, ``"cm"``, ``"mm"``, ``"inch"``, ``"BVH units"`` (no unit made the body
  human-sized; lengths scaled so that its stature is 1.75 m) or the caller's unit.
  ``skeleton.file_unit`` holds the metres per file unit in every case.
* ``unit_note``: present when the unit was not detected: why ("given by the caller", or
  how a "BVH units" body was scaled).
* ``stature_m``: the body's stature in metres (:func:`units.estimate_stature`).
* ``bvh_root_channels``: the channel list of the Motion's root joint, in file order.
* ``bvh_hierarchy``: the file's layout, for writing back onto the user's rig::

      {"file_unit": metres per file unit,
       "dropped": [names of the ancestors removed by re-rooting, top first],
       "nodes": [one dict per ROOT / JOINT / End Site, in file order:
           {"name": name in the file (an End Site's name token, None when it has none),
            "joint": the Skeleton joint's name, None for a dropped ancestor,
            "parent": index into "nodes", -1 for the file's root,
            "offset": [x, y, z] the OFFSET as written in the file,
            "channels": ["Xposition", ..., "Yrotation"] in file order,
            "end_site": bool,
            "values": (dropped ancestors only) one value per channel that a writer puts
                      in every frame: the file's own when constant, else 0 (rotations,
                      root positions) or the OFFSET component (other positions)}]}

  The dropped ancestors are always ``nodes[0 .. len(dropped) - 1]``, one chain; the
  Skeleton's joints are the remaining nodes, in the same order.
* ``bvh_position_spread_m``: {joint name: metres} for joints other than the root whose
  position channels move: their mean became the offset, this is the largest distance of
  a frame's value from it (empty when every such channel is constant).

Re-rooting: when the root's only child, or its only grandchild and so on down a single
chain, has animated position channels (Bandai Namco's ``joint_Root`` -> ``Hips``), the Motion
is rooted at the deepest such joint: root translation = its world position, root rotation =
its world rotation as an Euler chain in its own channel order (the file's angles unchanged
when the ancestors never rotate). Whether the dropped ancestors move does not matter.
"""
from __future__ import annotations

import numpy as np

from motionlang.formats.bvh_build import MAX_ABS
from motionlang.formats.bvh_read import read_bvh
from motionlang.formats.bvh_write import write_bvh
from motionlang.formats.units import UNITS, detect_unit, estimate_stature


def guess_unit(positions: np.ndarray) -> float:
    """Metres per file unit for joint positions (J, 3) or (T, J, 3) in file units (the
    unit :func:`read_bvh` would choose for that body)."""
    return detect_unit(estimate_stature(positions))[1]


__all__ = ["read_bvh", "write_bvh", "guess_unit", "UNITS", "MAX_ABS"]

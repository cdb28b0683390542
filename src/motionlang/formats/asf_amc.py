"""Acclaim ASF (skeleton) / AMC (motion) files, as used by the CMU motion capture database.

The agreed import point of the ASF/AMC API; the code lives in :mod:`motionlang.formats.asf`
(skeletons, file conventions) and :mod:`motionlang.formats.amc` (motions, channel arrays).
"""
from motionlang.formats.amc import (
                                    motion_from_channels,
                                    motion_to_channels,
                                    read_amc,
                                    read_asf_amc,
                                    write_amc,
)
from motionlang.formats.asf import INCH, read_asf

__all__ = ["INCH", "motion_from_channels", "motion_to_channels", "read_amc", "read_asf",
           "read_asf_amc", "write_amc"]

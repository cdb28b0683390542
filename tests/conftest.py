"""Shared fixtures: the real data folder and a tiny motion. Helpers that tests import
live in :mod:`helpers` (this folder's ``helpers/``), not here."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from helpers.data import SHARED
from helpers.mocap import tiny_skeleton
from motionlang.kinematics import Motion


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ../shared/data; tests that use it skip cleanly where it is absent."""
    if not SHARED.is_dir():
        pytest.skip(f"real data folder {SHARED} not present")
    return SHARED


@pytest.fixture
def tiny_motion() -> Motion:
    rng = np.random.default_rng(0)
    sk = tiny_skeleton()
    T = 20
    return Motion(sk, 30.0, rng.normal(size=(T, 3)), rng.uniform(-1, 1, (T, 3)),
                  rng.uniform(-1, 1, (T, sk.ndof)), name="tiny")

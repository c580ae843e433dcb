"""Fixtures shared by the runtime tests: the Panda and its C kinematics (tests that need another
robot or backend define their own ``panda``/``kin``, which take precedence)."""

from __future__ import annotations

import pytest

import symkin


@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


@pytest.fixture(scope="module")
def kin(panda):
    return symkin.compile(panda, backend="c")

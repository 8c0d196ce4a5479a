"""Fixtures for the kinematics tests: the real arm models loaded from config/arms/."""

import pytest

from armlab.kinematics import load_arm


@pytest.fixture(scope="session")
def rx200():
    return load_arm("rx200")


@pytest.fixture(scope="session")
def ur3():
    return load_arm("ur3")

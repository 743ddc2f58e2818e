"""Fixtures of the core tests: the report's IRB-140 and its derived torque limits."""

import pytest

from irb140_dynamics.core import derive_torque_limits, irb140


@pytest.fixture(scope="module")
def model():
    return irb140()


@pytest.fixture(scope="module")
def limits(model):
    return derive_torque_limits(model)

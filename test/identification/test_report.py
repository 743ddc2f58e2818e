"""The report's published torques (section 9 and 10), reproduced by the core."""

import math

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, gravity, irb140, load_model, rnea
from irb140_dynamics.core.io.params_file import read_parameter_file

from ..support.paths import CONFIG

STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]
NO_PAYLOAD = [0.0, 243.382, 79.1556, 0.0, 2.43004, 0.0]
SIX_KG = [0.0, 290.765, 105.348, 0.0, 6.25594, 0.0]
# The appendix A.3 Mathematica output, to all its digits.
MATHEMATICA = [0.0, 243.3824141750203, 79.15555672137201, 0.0, 2.430038123143249, 0.0]


@pytest.fixture(params=["geometry", "config"])
def model(request):
    """The IRB-140 built from the report's shapes, and as read from config/irb140.yaml."""
    return irb140() if request.param == "geometry" else load_model(CONFIG)


def test_no_payload(model):
    zeros = np.zeros(6)
    np.testing.assert_allclose(rnea(model, STRETCHED, zeros, zeros), NO_PAYLOAD, atol=1e-3)
    np.testing.assert_allclose(gravity(model, STRETCHED), MATHEMATICA, rtol=1e-14, atol=1e-12)


def test_six_kg_point_mass_at_frame_6_origin(model):
    loaded = model.with_payload(RigidBody(6.0))
    np.testing.assert_allclose(gravity(loaded, STRETCHED), SIX_KG, atol=1e-3)


def test_payload_adds_its_weight_times_reach():
    # Stretched arm: the 6 kg sits 0.805 m out from joint 2, 0.445 m from joint 3, 0.065 m from 5.
    extra = gravity(irb140(payload=RigidBody(6.0)), STRETCHED) - gravity(irb140(), STRETCHED)
    np.testing.assert_allclose(extra, 6.0 * 9.81 * np.array([0, 0.805, 0.445, 0, 0.065, 0]), atol=1e-12)


def test_config_file_is_the_geometry_model():
    assert load_model(CONFIG) == irb140()
    assert read_parameter_file(CONFIG)["joint_names"] == [f"joint_{i}" for i in range(1, 7)]

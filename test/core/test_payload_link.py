"""payload.link (core.io.arm_source.read_arm): the payload on a URDF link of a chain, against
Pinocchio with the payload appended at that link's frame; a link the model does not move
refused in one line naming payload.link."""

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import RigidBody, gravity
from irb140_dynamics.core.io.arm_source import read_arm
from irb140_dynamics.core.io.urdf import load_urdf

from ..support.urdf_support import ARMS, arm_text, pinocchio_of

PAYLOAD = RigidBody(3.0, (0.02, -0.01, 0.04), (0.02, 0.01, 0.015, 0.0, 0.001, 0.0))


def ur5_values(**values):
    given = {"model.source": "robot_description", "robot_description": arm_text("ur5"), "model.tip_link": "tool0"}
    return given | {"payload.mass": PAYLOAD.mass, "payload.com": list(PAYLOAD.com)} | values


@pytest.mark.parametrize("link", ["wrist_2_link", "tool0"])
def test_a_payload_on_a_link_of_the_chain_is_pinocchios(link):
    model = read_arm(ur5_values(**{"payload.link": link, "payload.inertia": list(PAYLOAD.inertia)})).model
    assert model.is_chain == (link == "tool0")
    text = arm_text("ur5")
    pm = pinocchio_of(text, load_urdf(text, tip_link="tool0").held_joints, link, PAYLOAD)
    for q in np.random.default_rng(11).uniform(-2.0, 2.0, (3, model.n)):
        expected = pin.computeGeneralizedGravity(pm, pm.createData(), q)
        np.testing.assert_allclose(gravity(model, q), expected, rtol=1e-9, atol=1e-9)


def test_a_link_the_model_does_not_move_is_refused_naming_payload_link():
    with pytest.raises(ValueError, match=r"^[^\n]*payload\.link: [^\n]*'base' is not moved by the model's joints$"):
        read_arm(ur5_values(**{"payload.link": "base"}))
    assert ARMS["ur5"][1] == "tool0"

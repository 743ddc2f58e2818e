"""docs/examples/markers.json, the recording docs/visualization.md draws, is what id_node
publishes on ~/markers for the state it was recorded from (regenerate it with
``IRB140_RECORD_MARKERS=1`` when the markers change on purpose)."""

import json
import os

import numpy as np
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from visualization_msgs.msg import Marker, MarkerArray

from irb140_dynamics.core import RigidBody, gravity, irb140
from irb140_dynamics.core.monitoring.wrench import flange_jacobian_in
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.marker_json import marker_dicts, marker_json
from ..support.paths import ROOT
from ..support.ros_harness import running

RECORDING = ROOT / "docs" / "examples" / "markers.json"
Q = np.array([0.4, -0.5, 0.6, 0.3, 0.9, 0.2])  # rad
PAYLOAD = RigidBody(4.0, (0.0, 0.0, 0.08))
PUSH = np.array([0.0, -40.0, -30.0, 0.0, 0.0, 0.0])  # N on the flange, base axes


def recorded_state_markers() -> MarkerArray:
    """id_node (payload 4 kg, joint 1's collision threshold 15 N m) fed the arm held at Q
    against gravity and PUSH for 0.1 s at 1 kHz: its last MarkerArray."""
    model = irb140(payload=PAYLOAD)
    effort = gravity(model, Q) - flange_jacobian_in(model, Q, "base").T @ PUSH
    overrides = [
        Parameter("markers.rate", value=20.0),
        Parameter("payload.mass", value=PAYLOAD.mass),
        Parameter("payload.com", value=list(PAYLOAD.com)),
        Parameter("joint_1.collision_threshold", value=15.0),
    ]
    with running(IdNode, parameter_overrides=overrides) as harness:
        markers = harness.listen(MarkerArray, "/id_node/markers")
        states = harness.publisher(JointState, "joint_states")
        for k in range(100):
            msg = JointState(name=list(model.joint_names), position=Q.tolist(), velocity=[0.0] * 6)
            msg.effort = effort.tolist()
            msg.header.stamp.sec, msg.header.stamp.nanosec = 10, k * 1_000_000
            states.publish(msg)
            harness.spin_for(0.001)
        last = lambda: markers and markers[-1].markers[0].header.stamp.nanosec == 99_000_000  # noqa: E731
        assert harness.spin_until(last)
        return markers[-1]


def test_the_recording_is_what_id_node_publishes():
    markers = recorded_state_markers()
    if os.environ.get("IRB140_RECORD_MARKERS"):
        RECORDING.write_text(marker_json(markers))
    recorded, published = json.loads(RECORDING.read_text()), marker_dicts(markers)
    assert [(m["ns"], m["id"], m["action"], m["text"]) for m in recorded] == [
        (m["ns"], m["id"], m["action"], m["text"]) for m in published
    ]
    for old, new in zip(recorded, published):  # 0.1 mm: 0.01 N of arrow (a joint state lost on a busy machine)
        for field in ("position", "scale", "color"):
            np.testing.assert_allclose(old[field], new[field], atol=1e-4)
        np.testing.assert_allclose(old["points"], new["points"], atol=1e-4)
    shown = {m["ns"] for m in recorded if m["action"] == Marker.ADD}
    assert shown == {"joint_load", "joint_label", "payload", "external_force", "collision"}

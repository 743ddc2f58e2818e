"""id_node's own parameters; the settings they give are core.trajectories.stream_settings'."""

from __future__ import annotations

from rclpy.parameter import Parameter

from irb140_dynamics.core.model.rigid_body import MAX_MASS
from irb140_dynamics.core.monitoring import collision as observer
from irb140_dynamics.ros.parameters.specs import MAX_TORQUE, QOS_PARAMETERS, Spec

MAX_GAIN = 1e6  # computed-torque gains
DEFAULT_KP, DEFAULT_KD = 400.0, 40.0  # 1/s^2, 1/s: natural frequency 20 rad/s, critically damped
MAX_MARKER_RATE = 100.0  # Hz

NODE_PARAMETERS = [
    Spec(
        "acceleration.mode",
        "zero",
        "qdd when no ~/reference gives it: 'zero', or 'differentiate' the measured velocities (low-pass "
        "filtered; for monitoring: as a command it would feed the measured acceleration back, "
        "so effort_commands never use it)",
    ),
    Spec(
        "acceleration.cutoff_frequency",
        20.0,
        "cut-off of the velocity differentiation filter",
        "Hz",
        minimum=1e-3,
        maximum=1e6,
    ),
    Spec(
        "reference_timeout",
        0.5,
        "a ~/reference is let go this long after its last point (node clock); 0 = never",
        "s",
        minimum=0.0,
        maximum=1e6,
    ),
    Spec(
        "effort_commands.enabled", False, "also publish torques on effort_commands (Float64MultiArray)", read_only=True
    ),
    Spec(
        "effort_commands.source",
        "feedforward",
        "which torques go to effort_commands: 'feedforward', 'gravity' or 'computed_torque'",
    ),
    Spec(
        "rated_payload.mass",
        6.0,
        "the rated payload the markers' torque limits are derived from, for joints without torque_limit "
        "(as payload_check_node's)",
        "kg",
        minimum=0.0,
        maximum=MAX_MASS,
    ),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec(
        "collision.observer_gain",
        observer.DEFAULT_GAIN,
        "gain K of the momentum observer: external torques are seen through a lag of time constant 1/K",
        "1/s",
        minimum=observer.MIN_GAIN,
        maximum=observer.MAX_GAIN,
    ),
    Spec(
        "external_wrench.frame",
        "tip",
        "axes of external_wrench: 'tip' (the tip link's, e.g. flange) or 'base' (the base link's); "
        "the torque is about the flange origin in both",
    ),
    Spec(
        "external_wrench.links",
        Parameter.Type.STRING_ARRAY,
        "URDF links whose wrenches are estimated jointly, each on external_wrench in its link's frame "
        "(a tree's); not given: the flange's",
        read_only=True,
    ),
    Spec(
        "markers.rate",
        10.0,
        "~/markers (visualization_msgs/MarkerArray) at most this often, after new joint states; 0 = off",
        "Hz",
        minimum=0.0,
        maximum=MAX_MARKER_RATE,
        read_only=True,
    ),
    Spec("ft_sensor.link", "", "link of the wrist F/T sensor (ft_wrench), on the last link; '' = off", read_only=True),
    Spec("ft_contact_wrench.frame", "sensor", "its axes: 'sensor' or 'base' (torque about the sensor's origin)"),
    Spec("ft_sensor.apply_load", False, "~/estimate_ft_load also sets payload.mass and payload.com"),
    *QOS_PARAMETERS,
]


def PER_JOINT_PARAMETERS(joint_names) -> list[Spec]:
    thresholds = [
        Spec(
            f"{name}.collision_threshold",
            0.0,
            "a collision is flagged while |external torque| exceeds this; 0 = off",
            "N m",
            minimum=0.0,
            maximum=MAX_TORQUE,
        )
        for name in joint_names
    ]
    gains = [
        Spec(f"{name}.{kind}", default, f"computed-torque {what} gain", unit, minimum=0.0, maximum=MAX_GAIN)
        for name in joint_names
        for kind, default, what, unit in (
            ("kp", DEFAULT_KP, "position", "1/s^2"),
            ("kd", DEFAULT_KD, "velocity", "1/s"),
        )
    ]
    return thresholds + gains

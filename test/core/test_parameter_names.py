"""The names an arm's reader knows (core.io.parameter_names): the model's for its joints (a
URDF's joints: only what its model takes from the parameters), the nodes' own; each unknown
name with the nearest known one, the parameter it lies under, or the joint the arm lacks."""

from irb140_dynamics.core.io.parameter_names import (
    UnknownName,
    known_parameter_names,
    unknown_lines,
    unknown_names,
)

JOINTS = ["joint_1", "joint_2", "arm-left.1"]


def test_the_known_names_follow_the_joints_and_the_source():
    known = known_parameter_names(JOINTS)
    assert {"joint_1.dh", "arm_left_1.link.mass", "joint_2.kp", "arm-left.1.kp", "qos.depth", "payload.mass"} <= known
    urdf = known_parameter_names(JOINTS, from_urdf=True)
    assert "joint_1.armature" in urdf and "joint_1.dh" not in urdf and "joint_1.link.mass" not in urdf
    assert not any(name.startswith("joint_3.") for name in known)


def test_each_unknown_name_is_told_with_its_nearest_parent_or_missing_joint():
    given = ["payload.masss", "joint_1.dh.a", "joint_3.torque_limit", "qos.depth", "zzzz"]
    unknown = unknown_names(given, known_parameter_names(JOINTS), JOINTS)
    assert unknown == [
        UnknownName("joint_1.dh.a", parent="joint_1.dh"),
        UnknownName("joint_3.torque_limit", "joint_2.torque_limit", joint="joint_3"),
        UnknownName("payload.masss", "payload.mass"),
        UnknownName("zzzz"),
    ]
    assert unknown_lines(unknown, " (ignored)") == [
        "unknown parameter joint_3.torque_limit (ignored): the arm has no joint joint_3; "
        "did you mean joint_2.torque_limit?",
        "unknown parameter payload.masss (ignored); did you mean payload.mass?",
        "unknown parameter zzzz (ignored)",
        "unknown parameter joint_1.dh.a (ignored): joint_1.dh is one parameter, not a mapping",
    ]

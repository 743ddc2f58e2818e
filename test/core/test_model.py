"""Model validation (each error names its parameter), the flat parameter form and YAML files."""

import math
from dataclasses import replace

import numpy as np
import pytest
import yaml

from irb140_dynamics.core import (
    DH,
    Joint,
    ModelError,
    RigidBody,
    RobotModel,
    forward_dynamics,
    irb140,
    load_model,
    mass_matrix,
    rnea,
)
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.io.params_file import nested, read_parameter_file

from ..support.common import OFFSET_PAYLOAD, random_model, random_rotation

NAN, INF = float("nan"), float("inf")
# An inertia with principal moments (1, 1, 3), turned so that all six entries are non-zero.
_R = random_rotation(np.random.default_rng(1))
_T = _R @ np.diag([1.0, 1.0, 3.0]) @ _R.T
TURNED_TRIANGLE_BREAKER = [_T[0, 0], _T[1, 1], _T[2, 2], _T[0, 1], _T[0, 2], _T[1, 2]]


def irb140_params() -> dict:
    return irb140(payload=OFFSET_PAYLOAD).to_params()


def assert_rejected(params, field, reason=""):
    """from_params raises ModelError for ``field``, its message starting with the field name."""
    with pytest.raises(ModelError) as error:
        RobotModel.from_params(params)
    assert error.value.field == field
    assert str(error.value).startswith(f"{field}: ")
    assert reason in str(error.value)


def changed(key, value) -> dict:
    params = irb140_params()
    params[key] = value
    return params


@pytest.mark.parametrize(
    "key", ["joint_names", "gravity", "joint_1.dh", "joint_4.link.mass", "joint_4.link.com", "joint_6.link.inertia"]
)
def test_missing_parameter(key):
    params = irb140_params()
    del params[key]
    assert_rejected(params, key, "missing")


def test_optional_parameters_have_defaults():
    params = irb140_params()
    for key in ["payload.mass", "payload.com", "payload.inertia", "joint_2.position_limits", "joint_2.torque_limit"]:
        del params[key]
    model = RobotModel.from_params(params)
    assert model.payload == RigidBody()
    assert model.joints[1].position_limits == (-math.pi, math.pi)
    assert model.joints[1].torque_limit == 0.0


@pytest.mark.parametrize(
    "key, value",
    [
        ("gravity", [0.0, -9.81]),
        ("joint_2.dh", [0.36, 0.0, 0.0]),
        ("joint_2.link.com", [0.0, 0.0, 0.0, 0.0]),
        ("joint_2.link.inertia", [1.0, 1.0, 1.0]),
        ("payload.com", [0.1, 0.2]),
        ("payload.inertia", [0.0] * 7),
        ("joint_3.position_limits", [-1.0, 0.0, 1.0]),
    ],
)
def test_wrong_length(key, value):
    assert_rejected(changed(key, value), key, "expected")


@pytest.mark.parametrize("key, value", [("gravity", 9.81), ("joint_2.position_limits", 1.0)])
def test_number_where_a_list_is_expected(key, value):
    assert_rejected(changed(key, value), key)


@pytest.mark.parametrize(
    "key, value",
    [
        ("gravity", [0.0, 0.0, NAN]),
        ("joint_1.dh", [0.0, INF, 0.2, 0.0]),
        ("joint_2.link.mass", NAN),
        ("joint_1.link.inertia", [NAN, 1.0, 1.0, 0.0, 0.0, 0.0]),
        ("payload.com", [0.0, 0.0, -INF]),
        ("joint_5.position_limits", [-INF, 1.0]),
        ("joint_6.torque_limit", NAN),
    ],
)
def test_non_finite(key, value):
    assert_rejected(changed(key, value), key, "finite")


@pytest.mark.parametrize("key", ["joint_3.link.mass", "payload.mass"])
def test_negative_mass(key):
    assert_rejected(changed(key, -0.5), key, ">= 0")


@pytest.mark.parametrize(
    "key, inertia",
    [("joint_2.link.inertia", [1.0, 1.0, 1.0, 2.0, 0.0, 0.0]), ("payload.inertia", [1.0, 1.0, -0.5, 0.0, 0.0, 0.0])],
)
def test_inertia_not_positive_semidefinite(key, inertia):
    assert_rejected(changed(key, inertia), key, "positive semi-definite")


@pytest.mark.parametrize(
    "key, inertia",
    [("joint_4.link.inertia", [1.0, 1.0, 3.0, 0.0, 0.0, 0.0]), ("payload.inertia", TURNED_TRIANGLE_BREAKER)],
)
def test_inertia_breaking_the_triangle_inequality(key, inertia):
    assert_rejected(changed(key, inertia), key, "triangle inequality")


def test_lower_limit_above_upper():
    assert_rejected(changed("joint_2.position_limits", [1.0, -1.0]), "joint_2.position_limits", "lower")


def test_negative_torque_limit():
    assert_rejected(changed("joint_1.torque_limit", -5.0), "joint_1.torque_limit", ">= 0")


def test_duplicate_joint_names():
    names = ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_1"]
    assert_rejected(changed("joint_names", names), "joint_names", "unique")


@pytest.mark.parametrize("bad_name", ["joint-1", "joint 1", "", "tab\tname", "x" * 201, 5, None])
def test_invalid_joint_name(bad_name):
    """Not a name (empty, too long, not printable, not a string), or one whose parameter
    prefix is another's ("joint-1" and "joint_1" both use joint_1.*)."""
    names = ["joint_1", bad_name, "joint_3"]
    assert_rejected(changed("joint_names", names), "joint_names")


@pytest.mark.parametrize(
    "name, prefix",
    [("2nd", "j_2nd"), ("arm-left.1", "arm_left_1"), ("_joint", "j__joint"), ("panda_joint1", "panda_joint1")],
)
def test_any_printable_joint_name_has_parameters_under_its_prefix(name, prefix):
    params = {k.replace("joint_2.", f"{prefix}.", 1): v for k, v in irb140().to_params().items()}
    params["joint_names"] = ["joint_1", name, "joint_3", "joint_4", "joint_5", "joint_6"]
    model = RobotModel.from_params(params)
    renamed = tuple(replace(j, name=name) if j.name == "joint_2" else j for j in irb140().joints)
    assert model == replace(irb140(), joints=renamed)
    assert RobotModel.from_params(model.to_params()) == model
    assert f"{prefix}.link.mass" in model.to_params()


@pytest.mark.parametrize("names", ["joint_1", 5])
def test_joint_names_not_a_list(names):
    assert_rejected(changed("joint_names", names), "joint_names")


def test_empty_joint_list():
    assert_rejected(changed("joint_names", []), "joint_names", "at least one joint")
    with pytest.raises(ModelError, match="^joint_names: "):
        RobotModel(())


@pytest.mark.parametrize(
    "key, value",
    [
        ("joint_1.dh", "abcd"),
        ("joint_2.link.mass", "heavy"),
        ("payload.com", ["a", 0.0, 0.0]),
        ("gravity", {"z": -9.81}),
        ("joint_1.torque_limit", [1.0, 2.0]),
        ("joint_2.link.mass", "5"),
        ("joint_1.torque_limit", True),
    ],
)
def test_non_numeric(key, value):
    assert_rejected(changed(key, value), key)


def test_direct_construction_is_validated_too():
    with pytest.raises(ModelError, match=r"^joint_names: "):
        RobotModel((Joint("bad\nname", DH()),))
    with pytest.raises(ModelError, match=r"^elbow\.link\.mass: "):
        RobotModel((Joint("elbow", DH(), RigidBody(-1.0)),))
    with pytest.raises(ModelError, match=r"^payload\.mass: "):
        irb140().with_payload(RigidBody(-1.0))
    with pytest.raises(ModelError, match=r"^gravity: "):
        irb140().with_gravity([0.0, -9.81])


@pytest.mark.parametrize("n", range(1, 8))
def test_params_round_trip(n):
    for model in (irb140(payload=OFFSET_PAYLOAD), random_model(np.random.default_rng(n), n)):
        params = model.to_params()
        params["use_sim_time"] = False  # other nodes' parameters are ignored
        assert RobotModel.from_params(params) == model


@pytest.fixture
def parameter_file(tmp_path):
    """A file with the IRB-140 for every node and overrides for the node "id_node"."""
    overrides = {"gravity": [0.0, 0.0, -9.80665], "payload": {"mass": 6.0, "com": [0.0, 0.0, 0.05]}}
    document = {
        "/**": {"ros__parameters": nested(irb140().to_params())},
        "id_node": {"ros__parameters": overrides},
        "/other_node": {"ros__parameters": {"gravity": [0.0, 0.0, 0.0]}},
    }
    path = tmp_path / "params.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


def test_read_parameter_file_wildcard_section(parameter_file):
    assert read_parameter_file(parameter_file)["joint_4.link.mass"] == irb140().joints[3].link.mass
    assert load_model(parameter_file) == irb140()


def test_read_parameter_file_node_section_overrides_wildcard(parameter_file):
    expected = irb140().with_payload(RigidBody(6.0, (0.0, 0.0, 0.05))).with_gravity([0.0, 0.0, -9.80665])
    assert load_model(parameter_file, "id_node") == expected
    assert load_model(parameter_file, "other_node").gravity == (0.0, 0.0, 0.0)  # written "/other_node"
    assert load_model(parameter_file, "unknown_node") == irb140()


def test_with_payload_merges_into_the_last_link_only():
    model = irb140()
    loaded = model.with_payload(OFFSET_PAYLOAD)
    assert loaded.payload == OFFSET_PAYLOAD and model.payload == RigidBody()
    assert loaded.joints == model.joints and loaded.gravity == model.gravity
    assert loaded.bodies[:-1] == model.bodies[:-1]

    # The union of link 6 and the payload, by hand: parallel axis theorem about the joint CoM.
    parts = [model.joints[-1].link, OFFSET_PAYLOAD]
    mass = sum(p.mass for p in parts)
    com = sum(p.mass * np.array(p.com) for p in parts) / mass
    inertia = np.zeros((3, 3))
    for p in parts:
        xx, yy, zz, xy, xz, yz = p.inertia
        r = np.array(p.com) - com
        inertia += np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) + p.mass * (r @ r * np.eye(3) - np.outer(r, r))
    merged = loaded.bodies[-1]
    assert merged.mass == pytest.approx(mass, rel=1e-15)
    np.testing.assert_allclose(merged.com, com, rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(merged.inertia, inertia[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]], rtol=1e-13, atol=1e-16)


# -- sanity caps: no parameter value that passes may overflow the algorithms ----------------------


@pytest.mark.parametrize(
    "key, value, reason",
    [
        ("payload.com", [1e200, 0.0, 0.0], "|com| must be <= 1000 m"),
        ("payload.mass", 1e200, "must be <= 1e+06 kg"),
        ("payload.mass", 1e308, "must be <= 1e+06 kg"),
        ("joint_2.link.mass", 2e6, "must be <= 1e+06 kg"),
        ("joint_4.link.com", [0.0, 1e3, 1.0], "|com| must be <= 1000 m"),
        ("payload.inertia", [1e7, 1e7, 1e7, 0.0, 0.0, 0.0], "|entry| must be <= 1e+06 kg m^2"),
        ("joint_3.dh", [0.0, 0.0, 1e200, 0.0], "|a| and |d| must be <= 1000 m"),
        ("gravity", [0.0, 0.0, -1e200], "|g| must be <= 1000 m/s^2"),
        ("joint_2.torque_limit", 1e300, "must be <= 1e+07 N m"),
    ],
)
def test_values_beyond_the_sanity_caps_are_refused(key, value, reason):
    assert_rejected(changed(key, value), key, reason)


def test_a_model_at_the_caps_stays_finite():
    """Every cap reached at once: the kernels compile (no inf or nan constant) and the
    torques, mass matrix and accelerations are finite at a brisk state."""
    heavy = RigidBody(1e6, (0.0, 0.0, 1e3), (1e6, 1e6, 1e6, 0.0, 0.0, 0.0))
    joints = tuple(Joint(f"j{i}", DH(a=1e3, alpha=math.pi / 2, d=1e3), heavy) for i in range(6))
    model = RobotModel(joints, (0.0, 0.0, -1e3), heavy)
    for body in model.bodies:  # the last one with the payload merged in
        m, h, inertia = body.about_origin()
        assert all(math.isfinite(x) for x in (m, *h, *inertia))
    q, qd, qdd = np.full(6, 0.7), np.full(6, 100.0), np.full(6, 1e4)
    assert np.isfinite(rnea(model, q, qd, qdd)).all()
    assert np.isfinite(mass_matrix(model, q)).all()
    assert np.isfinite(forward_dynamics(model, q, qd, np.zeros(6))).all()


# -- validated once: a model rebuilt for another payload re-validates no joint ------------------


def test_a_payload_change_reuses_the_validated_joints_and_links(monkeypatch):
    from irb140_dynamics.core.model import joints as joints_module

    params = irb140_params()
    first = RobotModel.from_params(params)
    validations = []
    validate = joints_module._validate_joint
    monkeypatch.setattr(joints_module, "_validate_joint", lambda j: validations.append(j.name) or validate(j))
    params["payload.mass"] = 2.5
    second = RobotModel.from_params(params)
    assert validations == []
    assert all(a is b for a, b in zip(first.joints, second.joints))
    assert second.payload.mass == 2.5
    assert kernels_of(second).links[:-1] == kernels_of(first).links[:-1]
    assert kernels_of(second).links[-1].m != kernels_of(first).links[-1].m
    state = [0.1] * 6, [0.2] * 6, [0.3] * 6
    expected = irb140(payload=RigidBody(2.5, OFFSET_PAYLOAD.com, OFFSET_PAYLOAD.inertia))
    np.testing.assert_array_equal(rnea(second, *state), rnea(expected, *state))  # the last link follows
    validations.clear()
    params["joint_3.link.mass"] = 30.0
    third = RobotModel.from_params(params)
    assert validations == ["joint_3"]
    assert third.joints[2].link.mass == 30.0 and third.joints[1] is second.joints[1]


@pytest.mark.parametrize("value", [True, 1, -0.0, np.float64(18.0)])
def test_a_remembered_joint_is_not_given_for_a_value_that_only_equals_its_values(value):
    """1.0 remembered does not answer for True (refused), nor 0.0 for -0.0, nor a float for
    an int: each value is validated as given."""
    params = irb140_params()
    field = "joint_1.velocity_limit"
    params[field] = float(value) if not isinstance(value, bool) else 1.0
    remembered = RobotModel.from_params(params)
    params[field] = value
    if isinstance(value, bool):
        assert_rejected(params, field, "expected numbers")
        return
    model = RobotModel.from_params(params)
    assert model.joints[0].velocity_limit == float(value)
    assert type(model.joints[0].velocity_limit) is float
    if value == 0.0:
        assert math.copysign(1.0, model.joints[0].velocity_limit) == math.copysign(1.0, value)
    assert model.joints[0] is not remembered.joints[0] or repr(value) == repr(float(value))

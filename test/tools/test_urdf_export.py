"""RobotModel -> URDF: the round trip gives the same dynamics, Pinocchio's parser agrees,
the IRB-140's visuals are the report's shapes, and urdf/irb140.urdf is what export gives."""

import dataclasses
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import gravity, irb140, load_model, mass_matrix, rnea
from irb140_dynamics.core.io.urdf import export_urdf, load_urdf
from irb140_dynamics.core.io.urdf.writer import inertia_box
from irb140_dynamics.core.model.irb140 import IRB140_SHAPES, Cylinder, box_inertia
from irb140_dynamics.core.model.joints import rpy_matrix
from irb140_dynamics.tools.export_urdf import urdf_of

from ..core.test_urdf_trees import TWO_ARMS
from ..support.common import OFFSET_PAYLOAD, assert_close, random_body, random_model, random_states, random_urdf_model
from ..support.node_process import run_to_exit
from ..support.paths import CONFIG, ROOT
from ..support.pinocchio_trees import worst_error
from ..support.urdf_support import full_mass_matrix, pinocchio_of

STATES = 200
EXPORTED = ROOT / "urdf" / "irb140.urdf"


def without_armature(model):
    """URDF has no armature: a model that has some cannot come back with it."""
    return dataclasses.replace(model, joints=tuple(dataclasses.replace(j, armature=0.0) for j in model.joints))


MODELS = {
    "irb140": lambda: irb140(payload=OFFSET_PAYLOAD),
    "random_dh_n7": lambda: random_model(np.random.default_rng(70), 7),
    "random_urdf_form_n6": lambda: without_armature(random_urdf_model(np.random.default_rng(60), 6, friction=True)),
    # a tree: a torso, two arms, mimic fingers (one before its joint, one prismatic), the flange on l2's link
    "tree_with_mimic_joints": lambda: dataclasses.replace(load_urdf(TWO_ARMS).model, flange_joint="l2"),
}


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def exported(request):
    """(model, URDF text, the model read back with the same payload and gravity, states)."""
    model = MODELS[request.param]()
    text = export_urdf(model)
    loaded = load_urdf(text)
    back = loaded.model if model.is_chain else loaded.with_flange_at("flange")  # a tree's: the flange named
    assert back.payload.mass == 0.0  # the payload is a node parameter, not written
    back = back.with_payload(model.payload).with_gravity(model.gravity)
    return model, text, back, random_states(np.random.default_rng(1), model.n, STATES)


def test_round_trip_gives_the_same_torques(exported):
    model, _, back, (Q, QD, QDD) = exported
    assert back.joint_names == model.joint_names
    assert (back.parent, back.mimics, back.carrier) == (model.parent, model.mimics, model.carrier)
    for q, qd, qdd in zip(Q, QD, QDD):
        assert_close(rnea(back, q, qd, qdd), rnea(model, q, qd, qdd), 1e-12, 1e-12, f"tau at q={q}")
        assert_close(gravity(back, q), gravity(model, q), 1e-12, 1e-12, f"g at q={q}")
        assert_close(mass_matrix(back, q), mass_matrix(model, q), 1e-12, 1e-12, f"M at q={q}")


def test_round_trip_keeps_limits_and_friction(exported):
    model, _, back, _ = exported
    for ours, theirs in zip(model.joints, back.joints):
        assert theirs.position_limits == ours.position_limits
        assert (theirs.torque_limit, theirs.velocity_limit) == (ours.torque_limit, ours.velocity_limit)
        assert theirs.friction == ours.friction


def test_pinocchio_parser_on_the_exported_text(exported):
    model, text, _, (Q, QD, QDD) = exported
    if model.mimics is not None:  # Pinocchio's model of every joint, projected (test.support.pinocchio_trees)
        assert worst_error(text, model, np.random.default_rng(2), states=5) <= 1e-12
        return
    pm = pinocchio_of(text, tip="flange", payload=model.payload, gravity=model.gravity)
    data = pm.createData()
    smooth = model.smoothing_velocity
    for q, qd, qdd in zip(Q, QD, QDD):
        expected = pin.rnea(pm, data, q, qd, qdd) + pm.damping * qd + pm.friction * np.tanh(qd / smooth)
        assert_close(rnea(model, q, qd, qdd), expected, 1e-12, 1e-12, f"tau at q={q}")
        assert_close(gravity(model, q), pin.computeGeneralizedGravity(pm, data, q), 1e-12, 1e-12, f"g at q={q}")
        assert_close(mass_matrix(model, q), full_mass_matrix(pm, data, q), 1e-12, 1e-12, f"M at q={q}")


def test_committed_irb140_urdf_is_what_export_gives():
    assert EXPORTED.read_text() == urdf_of(load_model(CONFIG)), (
        "regenerate: python -m irb140_dynamics.tools.export_urdf > urdf/irb140.urdf"
    )


def _pose(element) -> np.ndarray:
    origin = element.find("origin")
    return [float(x) for x in origin.get("xyz").split()], rpy_matrix([float(x) for x in origin.get("rpy").split()])


def test_irb140_visuals_are_the_report_shapes_at_each_centre_of_mass():
    model = irb140()
    robot = ET.fromstring(urdf_of(model))
    drawn = {}
    for i, joint in enumerate(model.joints):
        link = robot.find(f"link[@name='link_{i + 1}']")
        visual = link.find("visual")
        if joint.name not in IRB140_SHAPES:
            assert visual is None and joint.link.mass == 0.0
            continue
        shape = IRB140_SHAPES[joint.name]
        centre, turn = _pose(visual)
        assert centre == pytest.approx(_pose(link.find("inertial"))[0], abs=1e-15)
        post = joint.post.rotation()  # the model's link frame in the URDF link's frame
        if isinstance(shape, Cylinder):
            cylinder = visual.find("geometry/cylinder")
            assert (float(cylinder.get("radius")), float(cylinder.get("length"))) == (shape.radius, shape.height)
            axis = np.eye(3)["xyz".index(shape.axis)]
            assert turn[:, 2] == pytest.approx(post @ axis, abs=1e-15)  # URDF cylinders lie along z
        else:
            size = tuple(float(x) for x in visual.find("geometry/box").get("size").split())
            assert size == shape.size
            assert turn == pytest.approx(post, abs=1e-15)
        drawn[joint.name] = shape
    assert drawn == IRB140_SHAPES
    assert robot.find("joint[@name='flange_joint']/child").get("link") == "flange"


def test_inertia_box_has_the_body_inertia():
    rng = np.random.default_rng(9)
    for _ in range(20):
        body = random_body(rng)
        sides, axes = inertia_box(body)
        assert np.linalg.det(axes) == pytest.approx(1.0)
        I = axes @ np.diag(box_inertia(body.mass, sides)[:3]) @ axes.T
        xx, yy, zz, xy, xz, yz = body.inertia
        assert_close(I, [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], 1e-12, 1e-15)


@pytest.mark.process
def test_export_urdf_tool_prints_the_committed_file_and_refuses_bad_input_in_one_line():
    import sys

    command = [sys.executable, "-m", "irb140_dynamics.tools.export_urdf"]
    code, output = run_to_exit(command)
    assert code == 0 and output == EXPORTED.read_text(), output[:500]
    code, output = run_to_exit(command + ["--ros-args", "-p", "joint_2.link.com:=[0.1, 0.0]"])
    assert code == 1 and output.count("\n") == 1 and "export_urdf: error: joint_2.link.com" in output, output


def test_exported_limits_are_positive_and_come_from_their_sources():
    """docs/urdf.md: the model's, else the data sheet's speeds and the derived torque limits,
    else (a joint no static payload loads) the rated payload at the acceleration limit."""
    import math

    from irb140_dynamics.core import RATED_PAYLOAD, derive_torque_limits
    from irb140_dynamics.tools.cli import ToolError
    from irb140_dynamics.tools.export_urdf import DATA_SHEET_SPEEDS, POSES, limits

    model = load_model(CONFIG)
    effort, velocity, sources = limits(model)
    derived = derive_torque_limits(model)
    speeds = [math.radians(s) for s in DATA_SHEET_SPEEDS]
    assert velocity == pytest.approx(speeds, rel=1e-15)  # config/irb140.yaml holds the data sheet's
    loaded = model.with_payload(RATED_PAYLOAD)
    rng_poses = {}
    for k, (e, d) in enumerate(zip(effort, derived.values)):
        assert e > 0 and math.isfinite(e)
        if math.isfinite(d):
            assert e == d and "static" in sources[k]
        else:  # joints 1 and 6: no gravity torque; the inertia about the axis at its acceleration limit
            lower, upper = np.array([j.position_limits for j in model.joints]).T
            q = np.random.default_rng(k).uniform(lower, upper, size=(POSES, model.n))
            M = np.array([mass_matrix(loaded, x)[k, k] for x in q])
            rng_poses[k] = M
            assert e == pytest.approx(M.max() * model.joints[k].acceleration_limit, rel=1e-9)
    assert sorted(rng_poses) == [0, 5]
    robot = ET.fromstring(urdf_of(model))
    written = [robot.find(f"joint[@name='{j.name}']/limit") for j in model.joints]
    assert [float(x.get("effort")) for x in written] == effort
    assert [float(x.get("velocity")) for x in written] == velocity

    no_speeds = dataclasses.replace(
        model, joints=tuple(dataclasses.replace(j, velocity_limit=0.0, torque_limit=50.0) for j in model.joints)
    )
    effort, velocity, _ = limits(no_speeds)
    assert effort == [50.0] * 6 and velocity == pytest.approx(speeds, rel=1e-15)
    other = dataclasses.replace(
        no_speeds, joints=tuple(dataclasses.replace(j, name=f"j{k}") for k, j in enumerate(no_speeds.joints))
    )
    with pytest.raises(ToolError, match="j0: no velocity_limit"):
        limits(other)

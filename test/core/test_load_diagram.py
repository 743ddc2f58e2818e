"""The load diagram: each proven mass is a certified lower bound of the largest payload the
arm holds at rest in every pose and every direction of the CoM about the flange axis, and
within 2 % of it. Checked against an independent search on Pinocchio (its own URDF parser
for the URDF arms): random poses and directions, then local optimisation from the worst."""

import importlib.metadata
import math
import os
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import minimize

from irb140_dynamics.core import Joint, RigidBody, RobotModel, derive_torque_limits, gravity, gravity_batch, irb140
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.payload import diagram as diagram_module
from irb140_dynamics.core.payload.diagram import load_diagram, pivoted
from irb140_dynamics.core.payload.proof.harmonic import StaticForms
from irb140_dynamics.core.urdf import export_urdf

from ..support.paths import URDF_DATA
from ..support.pinocchio_model import build
from ..support.urdf_support import ARMS, arm_text, pinocchio_of

DIRECTIONS = np.linspace(-math.pi, math.pi, 16, endpoint=False)


class Independent:
    """The largest payload of CoM (l cos phi, l sin phi, z) at pose q by Pinocchio's gravity
    torques: linear in the payload's mass and first moment, so five models give them all."""

    def __init__(self, models, limits, lower, upper):
        self.models = models  # payload none, 1 kg at the origin, at x, y, z = 1 m
        self.data = [m.createData() for m in models]
        self.limits, self.lower, self.upper = np.asarray(limits, dtype=float), lower, upper

    def torques(self, q):
        return [pin.computeGeneralizedGravity(m, d, q)[: self.lower.size] for m, d in zip(self.models, self.data)]

    def mass(self, q, phi, z, l):
        """The largest mass that pose q holds with the CoM at direction phi (inf: unbounded)."""
        G0, origin, x, y, up = self.torques(np.clip(q, self.lower, self.upper))
        dG = origin + l * math.cos(phi) * (x - origin) + l * math.sin(phi) * (y - origin) + z * (up - origin) - G0
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(dG > 0, (self.limits - G0) / dG, np.where(dG < 0, (self.limits + G0) / -dG, np.inf))
        return float(np.min(np.where(np.isfinite(self.limits), room, np.inf)))

    def search(self, z, l, rng, poses=3000, climbs=6) -> float:
        """Dense random poses and directions, then Powell from the worst ones."""
        Q = self.lower + rng.random((poses, self.lower.size)) * (self.upper - self.lower)
        phi = rng.uniform(-math.pi, math.pi, poses)
        values = np.array([self.mass(q, p, z, l) for q, p in zip(Q, phi)])
        best = float(values.min())
        bounds = list(zip(self.lower, self.upper)) + [(-math.pi, math.pi)]
        for i in np.argsort(values)[:climbs]:
            found = minimize(
                lambda x: self.mass(x[:-1], x[-1], z, l),
                np.append(Q[i], phi[i]),
                method="Powell",
                bounds=bounds,
                options={"xtol": 1e-6, "ftol": 1e-10, "maxfev": 4000},
            )
            best = min(best, float(found.fun))
        return best


def payload_models(build_with):
    bodies = [RigidBody(0.0), RigidBody(1.0)] + [RigidBody(1.0, tuple(np.eye(3)[k])) for k in range(3)]
    return [build_with(body) for body in bodies]


def irb140_case():
    model = irb140()
    limits = derive_torque_limits(model).values
    models = payload_models(lambda body: build(model.with_payload(body)))
    return model, limits, models


def urdf_case(name):
    text, tip = arm_text(name), ARMS[name][1]
    loaded = load_urdf(text, tip_link=tip)
    models = payload_models(lambda body: pinocchio_of(text, loaded.held_joints, tip, body))
    return loaded.model, loaded.model.torque_limits, models


WALL = (0.0, -9.81 * math.sin(0.6), -9.81 * math.cos(0.6))  # mounted on a tilted wall: every joint is loaded


def prismatic_case():
    """The corpus's revolute-prismatic-revolute arm (to its tip ``hand``), its URDF efforts."""
    text = (URDF_DATA / "prismatic_arm.urdf").read_text()
    model = load_urdf(text).model.with_gravity(WALL)
    models = payload_models(lambda body: pinocchio_of(text, (), "hand", body, WALL))
    return model, model.torque_limits, models


def gantry():
    """A 9-joint arm: the IRB-140 on a 3-axis gantry (x, y, z prismatic, 15 kg carriages)."""
    arm = irb140()
    carriage = RigidBody(15.0, (0.0, 0.0, 0.05), (0.3, 0.3, 0.3, 0.0, 0.0, 0.0))
    slides = [
        Joint(f"gantry_{name}", link=carriage, position_limits=(0.0, 1.5), axis=axis, kind="prismatic")
        for name, axis in (("x", (1.0, 0.0, 0.0)), ("y", (0.0, 1.0, 0.0)), ("z", (0.0, 0.0, 1.0)))
    ]
    return RobotModel(tuple(slides) + arm.joints, arm.gravity)


def gantry_case():
    """The gantry, its limits derived; Pinocchio's models from its URDF (Pinocchio's parser)."""
    model = gantry()
    text = export_urdf(model, name="gantry_irb140")
    models = payload_models(lambda body: pinocchio_of(text, (), "flange", body))
    return model, derive_torque_limits(model).values, models


def example_robot_text(name: str) -> str | None:
    """The text of an example-robot-data URDF by its file name (None: not installed)."""
    try:
        distribution = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    found = [f for f in distribution.files or () if str(f).endswith("/" + name)]
    return distribution.locate_file(found[0]).read_text() if found else None


def talos_case():
    """A 9-joint chain whose joints all turn one another: TALOS's torso and left arm
    (example-robot-data). Its URDF's efforts do not hold the arm itself, and with the limits
    a 6 kg payload derives the arm alone loads the wrist more in some poses (the payload's
    weight offsets the wrist's own): the limits are 20 % above those."""
    text = example_robot_text("talos_reduced.urdf")
    if text is None:
        pytest.skip("example-robot-data is not installed")
    loaded = load_urdf(text, base_link="base_link", tip_link="arm_left_7_link")
    model = replace(loaded.model, joints=tuple(replace(j, torque_limit=0.0) for j in loaded.model.joints))
    moving = set(model.joint_names)
    held = [
        j.get("name")
        for j in ET.fromstring(text).findall("joint")
        if j.get("type") != "fixed" and j.get("name") not in moving
    ]
    models = payload_models(
        lambda body: pinocchio_of(text, held, "arm_left_7_link", body)
    )  # (the other limbs held at 0)
    return model, 1.2 * np.array(derive_torque_limits(model).values), models


def xarm7_case():
    """A 7-joint arm whose shoulder the arm's own weight loads to about 70 % of its limit,
    with its rolls (joints 3, 5, 7) turning whole turns: the xArm7 of example-robot-data,
    its URDF efforts."""
    text = example_robot_text("xarm7.urdf")
    if text is None:
        pytest.skip("example-robot-data is not installed")
    loaded = load_urdf(text, tip_link="link_eef")
    models = payload_models(lambda body: pinocchio_of(text, loaded.held_joints, "link_eef", body))
    return loaded.model, loaded.model.torque_limits, models


CASES = {
    "irb140": irb140_case,
    "gantry_irb140": gantry_case,
    "ur5": lambda: urdf_case("ur5"),
    "panda": lambda: urdf_case("panda"),
    "prismatic_arm": prismatic_case,
    "talos_arm": talos_case,
    "xarm7": xarm7_case,
}
GRIDS = {
    "irb140": ([0.0, 0.12], [0.0, 0.08]),
    "ur5": ([0.0, 0.15], [0.0, 0.1]),
    "panda": ([0.15], [0.0, 0.1]),  # an on-axis and an off-axis point each (the proof's two kinds)
    "talos_arm": ([0.1], [0.05]),
    "xarm7": ([0.2], [0.15]),
    "gantry_irb140": ([0.1], [0.0, 0.1]),
    "prismatic_arm": ([0.0, 0.2], [0.0, 0.1]),
}


def test_the_pivot_turns_the_payload_about_the_flange_axis():
    """The pivoted arm's torques with the payload at (l, 0, z) and the extra joint at phi are
    Pinocchio's of the arm with the payload at (l cos phi, l sin phi, z)."""
    rng = np.random.default_rng(3)
    model = irb140()
    arm = pivoted(model)
    for _ in range(5):
        z, l, phi, m = rng.uniform(0, 0.3), rng.uniform(0, 0.2), rng.uniform(-math.pi, math.pi), rng.uniform(0.5, 5)
        q = rng.uniform(-2, 2, model.n)
        ours = gravity(arm.with_payload(RigidBody(m, (l, 0.0, z))), np.append(q, phi))
        turned = model.with_payload(RigidBody(m, (l * math.cos(phi), l * math.sin(phi), z)))
        theirs = pin.computeGeneralizedGravity(build(turned), build(turned).createData(), q)
        np.testing.assert_allclose(ours[:-1], theirs, atol=1e-10)


def test_forms_mixed_from_four_enclose_the_direct_ones():
    """A point's forms, mixed from four, hold the same sums as those made for its CoM."""
    arm = pivoted(irb140())
    shapes = diagram_module._Shapes(arm)
    mixed = shapes.family(0.13, 0.07).forms[1]
    direct = StaticForms.of(arm.with_payload(RigidBody(1.0, (0.07, 0.0, 0.13))))
    for a, b in [(mixed.torque, direct.torque)] + list(zip(mixed.omega, direct.omega)):
        assert (a.coefficients.lo <= b.coefficients.hi + 1e-12).all()
        assert (b.coefficients.lo <= a.coefficients.hi + 1e-12).all()
        np.testing.assert_allclose(a.coefficients.mid, b.coefficients.mid, atol=1e-11)


PROVEN_WITH = {}  # arm -> the shapes its diagram below was proven with


@pytest.mark.slow
@pytest.mark.parametrize("arm", sorted(CASES))
def test_proven_masses_are_below_the_true_maximum_and_within_2_percent(arm):
    model, limits, models = CASES[arm]()
    z, l = GRIDS[arm]
    diagram = load_diagram(model, limits, z, l)
    if arm == "gantry_irb140":  # its shapes, made once: see test_nine_moving_joints_get_the_harmonic_proof
        PROVEN_WITH[arm] = diagram_module._arm_of(model)[1]
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    independent = Independent(models, limits, lower, upper)
    rng = np.random.default_rng(11)
    assert diagram.proven_share == 1.0, [p.reason for p in diagram.points]
    for p in diagram.points:
        found = independent.search(p.z, p.l, rng)
        assert p.mass <= found * (1 + 1e-9), (p.z, p.l, p.mass, found)  # a real pose holds no more
        assert p.mass >= 0.98 * found, (p.z, p.l, p.mass, found)


def test_nine_moving_joints_get_the_harmonic_proof():
    """Up to 9 moving joints (10 angles with the CoM's direction) the diagram's proof is the
    harmonic one (the gantry's, as its diagram above was proven if it ran); beyond, plain
    interval bounds."""
    nine = PROVEN_WITH.get("gantry_irb140") or diagram_module._Shapes(pivoted(gantry()))
    assert nine.arm.n == 10 and nine.forms is not None
    ten = RobotModel((replace(gantry().joints[0], name="gantry_w"),) + gantry().joints, irb140().gravity)
    assert diagram_module._Shapes(pivoted(ten)).forms is None


def test_the_mass_is_the_minimum_over_directions_not_one_direction():
    """Off the axis the diagram holds for every direction: below what any one direction
    allows, as the independent search over directions shows on the IRB-140."""
    model, limits, models = irb140_case()
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    independent = Independent(models, limits, lower, upper)
    point = load_diagram(model, limits, [0.05], [0.1]).points[0]
    q = np.zeros(model.n)
    per_direction = [independent.mass(q, phi, 0.05, 0.1) for phi in DIRECTIONS]
    assert point.proven and point.mass <= min(per_direction)


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("IRB140_FULL_SWEEP"), reason="the full sweep: set IRB140_FULL_SWEEP=1")
def test_full_irb140_sweep_is_proven_and_below_the_independent_search():
    model, limits, models = irb140_case()
    z, l = np.arange(31) * 0.01, np.arange(21) * 0.01
    diagram = load_diagram(model, limits, z, l, workers=2)
    assert diagram.proven_share >= 0.9
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    independent = Independent(models, limits, lower, upper)
    rng = np.random.default_rng(12)
    for p in diagram.points[::7]:
        found = independent.search(p.z, p.l, rng, poses=1500, climbs=3)
        assert p.mass <= found * (1 + 1e-9) and (not p.proven or p.mass >= 0.98 * found), (p.z, p.l, p.mass, found)


def test_a_prismatic_joint_is_an_angle_of_the_proof():
    """The proof's sums of an arm with a prismatic joint, at d = c + r sin(theta), are its
    static torques; and the angles map back to the displacements."""
    text = (URDF_DATA / "prismatic_arm.urdf").read_text()
    model = load_urdf(text).model.with_gravity(WALL).with_payload(RigidBody(2.0, (0.05, 0.02, 0.1)))
    forms = StaticForms.of(model)
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    q = lower + np.random.default_rng(4).random((50, model.n)) * (upper - lower)
    theta = forms.angles_of(q)  # (URDF joints: no angle offsets)
    np.testing.assert_allclose(forms.joints_of(theta), q, atol=1e-12)
    np.testing.assert_allclose(forms.torque(theta), gravity_batch(model, q), atol=1e-9)
    assert [cr is not None for cr in forms.sliding] == [j.prismatic for j in model.joints]


def test_the_worst_direction_is_a_lever_and_the_wrist_angle_drops_out():
    """On the Panda (link 7's CoM off its axis), joint 2's sum over the pose and the CoM's
    direction phi is A + X cos(phi) + Y sin(phi); without joint 7, A0 + |(P, Q)| + |(X0,
    Y0)| is the largest value over every turn of joint 7 and every direction."""
    from irb140_dynamics.core.payload.proof.harmonic import without_wrist

    model, _, _ = urdf_case("panda")
    arm = pivoted(model)
    forms = diagram_module._Shapes(arm).family(0.05, 0.1).forms
    torque = forms[0].affine(forms[1], 2.0).torque[1]  # joint 2's
    parts = torque.over_direction()
    lower, upper = np.array([j.position_limits for j in arm.joints]).T
    theta = lower + np.random.default_rng(6).random((40, arm.n)) * (upper - lower)
    A, X, Y = parts(theta[:, :-1]).T
    phi = theta[:, -1]
    np.testing.assert_allclose(A + X * np.cos(phi) + Y * np.sin(phi), torque(theta), atol=1e-9)
    wrist = without_wrist(parts)
    assert wrist is not None and wrist.dims == parts.dims[:-1]
    A0, P, Q, X0, Y0 = wrist(theta[:, :-2]).T
    bound = A0 + np.hypot(P, Q) + np.hypot(X0, Y0)
    turns = np.linspace(-math.pi, math.pi, 3601)
    for k in range(5):  # the worst direction of each turn of joint 7 (A + |(X, Y)|, as checked above)
        grid = np.repeat(theta[k : k + 1, :-1], turns.size, axis=0)
        grid[:, -1] = turns
        A, X, Y = parts(grid).T
        worst = np.max(A + np.hypot(X, Y))
        assert bound[k] - 1e-6 <= worst <= bound[k] + 1e-9, (worst, bound[k])


def test_an_arm_that_cannot_hold_itself_has_no_mass_anywhere():
    """Joint 2 limited below the arm's own weight: no point holds any mass, none is proven."""
    model = irb140()
    limits = np.array(derive_torque_limits(model).values)
    limits[1] = 1.0
    diagram = load_diagram(model, limits, [0.0, 0.1], [0.0])
    assert diagram.proven_share == 0.0
    assert all(math.isnan(p.mass) and p.reason for p in diagram.points), [p.reason for p in diagram.points]


@pytest.mark.parametrize("arm, z, l", [("irb140", 0.1, 0.05), ("ur5", 0.15, 0.1)])
def test_a_check_of_one_point_is_the_proof_there_and_agrees_with_the_independent_search(arm, z, l):
    """``check_point`` proves the point itself: its proven mass is the diagram's there, a
    mass a little under the independent search's is inside, one a little over it is not
    (a real pose then exceeds a limit), with the limiting joint and the margin in kg."""
    from irb140_dynamics.core.payload.diagram import check_point

    model, limits, models = CASES[arm]()
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    found = Independent(models, limits, lower, upper).search(z, l, np.random.default_rng(13))
    point = load_diagram(model, limits, [z], [l]).points[0]
    inside = check_point(model, limits, 0.97 * found, z, l)
    assert inside.inside and inside.proven == point.mass and inside.joint == model.joint_names[point.joint]
    assert inside.margin == pytest.approx(point.mass - 0.97 * found)
    assert inside.proven <= found * (1 + 1e-9)  # a lower bound of what a real pose holds
    outside = check_point(model, limits, 1.01 * found, z, l)
    assert not outside.inside and outside.margin < 0 and outside.joint == inside.joint
    assert outside.margin == pytest.approx(outside.found - 1.01 * found)
    assert outside.sentence().startswith(f"outside: {1.01 * found:g} kg at Z {z:g} m, L {l:g} m")


def test_a_mass_between_the_proven_and_the_found_is_proven_at_itself():
    """Between the grid proof's mass (99.5 % of the found one) and the found mass, the
    check proves the asked mass itself: inside where that proof closes."""
    from irb140_dynamics.core.payload.diagram import check_point

    model, limits, _ = irb140_case()
    point = load_diagram(model, limits, [0.1], [0.0]).points[0]
    between = point.mass + 0.3 * (point.found - point.mass)
    check = check_point(model, limits, between, 0.1, 0.0)
    assert check.inside and check.proven == between and check.margin == 0.0
    assert "holds in every pose and direction (proven)" in check.sentence()

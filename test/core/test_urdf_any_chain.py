"""Any serial chain a URDF holds: prismatic joints mixed with revolute and continuous
ones, fixed joints anywhere, names no parameter could carry, a base turned any way from
the root. Each against Pinocchio's reading of the same text (its whole tree, the joints
off the chain at zero), and through every part of the core that takes a model."""

import math

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import (
    RigidBody,
    RobotModel,
    check_payload,
    coriolis,
    coriolis_matrix,
    flange_jacobian,
    flange_pose,
    forward_dynamics,
    gravity,
    gravity_batch,
    mass_matrix,
    mass_matrix_batch,
    rnea,
    rnea_batch,
)
from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms.momentum import energy_gradient, momentum_terms
from irb140_dynamics.core.regressor import inertial_parameters, regressor, regressor_batch
from irb140_dynamics.core.scalars.dual import dual_angles, partial
from irb140_dynamics.core.urdf import export_urdf, load_urdf

NAMES = ("arm-left.1", "panda_joint2", "2nd joint", "j_3", "wrist/roll", "ä-joint", "x")


def _numbers(values) -> str:
    return " ".join(repr(float(x)) for x in values)


def _origin(rng, scale=0.3) -> str:
    rpy = [
        float(rng.choice([0.0, math.pi / 2, -math.pi])) if rng.random() < 0.4 else rng.uniform(-3, 3) for _ in range(3)
    ]
    return f'<origin xyz="{_numbers(rng.uniform(-scale, scale, 3))}" rpy="{_numbers(rpy)}"/>'


def _link(name, rng) -> str:
    moments = rng.uniform(0.01, 0.1, 3)
    xx, yy, zz = (float(x) for x in moments.sum() - moments)  # moments obeying the triangle inequality
    return (
        f'<link name="{name}"><inertial>{_origin(rng, 0.1)}<mass value="{float(rng.uniform(0.5, 3))!r}"/>'
        f'<inertia ixx="{xx!r}" iyy="{yy!r}" izz="{zz!r}" ixy="0" ixz="0" iyz="0"/></inertial></link>'
    )


def _joint(name, kind, parent, child, rng) -> str:
    axis = rng.normal(size=3) if rng.random() < 0.5 else np.eye(3)[rng.integers(3)]
    limit = '<limit lower="-1" upper="1" effort="80" velocity="2"/>' if kind != "fixed" else ""
    damping = f'<dynamics damping="{float(rng.uniform(0, 0.5))!r}"/>' if kind != "fixed" else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{_origin(rng)}'
        f'<axis xyz="{_numbers(axis / np.linalg.norm(axis))}"/>{limit}{damping}</joint>'
    )


def chain_urdf(rng, kinds) -> str:
    """root -> (a turned, moving mount) -> base -> the chain of ``kinds`` with fixed joints
    between, a side branch off each link, a fixed tip."""
    parts = [
        '<robot name="any">',
        _link("root", rng),
        _link("mount", rng),
        _link("base", rng),
        _joint("to_mount", "revolute", "root", "mount", rng),
        _joint("to_base", "fixed", "mount", "base", rng),
    ]
    parent = "base"
    for i, kind in enumerate(kinds):
        name = NAMES[i % len(NAMES)] + ("" if i < len(NAMES) else str(i))
        parts += [
            _joint(name, kind, parent, f"link {i}", rng),
            _link(f"link {i}", rng),
            _joint(f"fixed-{i}", "fixed", f"link {i}", f"fixed.{i}", rng),
            _link(f"fixed.{i}", rng),
            _joint(f"side-{i}", "prismatic", f"link {i}", f"side.{i}", rng),
            _link(f"side.{i}", rng),
        ]
        parent = f"fixed.{i}"
    parts += [_joint("to_tip", "fixed", parent, "tip", rng), '<link name="tip"/>', "</robot>"]
    return "\n".join(parts)


KINDS = {
    "prismatic_first": ["prismatic", "revolute", "revolute", "continuous"],
    "mixed": ["revolute", "prismatic", "continuous", "prismatic", "revolute", "revolute"],
    "all_prismatic": ["prismatic", "prismatic", "prismatic"],
    "one_revolute": ["revolute"],
}


class Pinocchio:
    """Pinocchio's whole-tree model of the text, the chain's joints at given values."""

    def __init__(self, text, names):
        self.model = pin.buildModelFromXML(text)
        self.data = self.model.createData()
        self.joints = [self.model.joints[self.model.getJointId(name)] for name in names]
        self.index = [j.idx_v for j in self.joints]

    def state(self, q, qd=None, qdd=None):
        pq, v, a = pin.neutral(self.model), np.zeros(self.model.nv), np.zeros(self.model.nv)
        for j, x, xd, xdd in zip(self.joints, q, qd if qd is not None else q * 0, qdd if qdd is not None else q * 0):
            if j.nq == 2:
                pq[j.idx_q : j.idx_q + 2] = math.cos(x), math.sin(x)
            else:
                pq[j.idx_q] = x
            v[j.idx_v], a[j.idx_v] = xd, xdd
        return pq, v, a

    def rnea(self, q, qd, qdd):
        tau = pin.rnea(self.model, self.data, *self.state(q, qd, qdd))[self.index]
        return tau + self.model.damping[self.index] * qd

    def gravity(self, q):
        return pin.computeGeneralizedGravity(self.model, self.data, self.state(q)[0])[self.index]

    def mass_matrix(self, q):
        M = pin.crba(self.model, self.data, self.state(q)[0])
        return (np.triu(M) + np.triu(M, 1).T)[np.ix_(self.index, self.index)]


def assert_close(ours, theirs, rtol=1e-9):
    theirs = np.asarray(theirs)
    assert np.max(np.abs(np.asarray(ours) - theirs)) <= rtol * max(1.0, np.max(np.abs(theirs)))


@pytest.fixture(params=list(KINDS), ids=list(KINDS))
def case(request):
    rng = np.random.default_rng(sorted(KINDS).index(request.param) + 23)
    text = chain_urdf(rng, KINDS[request.param])
    loaded = load_urdf(text, "base", "tip")
    return text, loaded, Pinocchio(text, loaded.model.joint_names), rng


def test_the_chain_is_read_with_its_kinds_and_names(case):
    text, loaded, _, _ = case
    model = loaded.model
    assert model.joint_names == tuple(NAMES[: model.n])
    assert len(loaded.held_joints) == model.n  # the side branches
    assert [j.kind for j in model.joints].count("prismatic") == sum(
        1 for name in model.joint_names if f'<joint name="{name}" type="prismatic"' in text
    )


def test_rnea_gravity_and_mass_matrix_agree_with_pinocchio(case):
    _, loaded, pinocchio, rng = case
    model = loaded.model
    for _ in range(5):
        q, qd, qdd = (rng.uniform(-1, 1, model.n) for _ in range(3))
        assert_close(rnea(model, q, qd, qdd), pinocchio.rnea(q, qd, qdd))
        assert_close(gravity(model, q), pinocchio.gravity(q))
        assert_close(mass_matrix(model, q), pinocchio.mass_matrix(q))
        M, bias = pinocchio.mass_matrix(q), pinocchio.rnea(q, qd, 0 * qd)
        assert_close(forward_dynamics(model, q, qd, M @ qdd + bias), qdd, 1e-7)


def test_batches_coriolis_and_its_matrix(case):
    _, loaded, pinocchio, rng = case
    model = loaded.model
    Q, QD, QDD = (rng.uniform(-1, 1, (4, model.n)) for _ in range(3))
    assert_close(rnea_batch(model, Q, QD, QDD), [rnea(model, *x) for x in zip(Q, QD, QDD)], 1e-12)
    assert_close(mass_matrix_batch(model, Q), [mass_matrix(model, q) for q in Q], 1e-12)
    for q, qd in zip(Q, QD):
        c = pinocchio.rnea(q, qd, 0 * qd) - pinocchio.gravity(q) - pinocchio.model.damping[pinocchio.index] * qd
        assert_close(coriolis(model, q, qd), c)
        C = coriolis_matrix(model, q, qd)
        assert_close(C @ qd, c)
        # Mdot - 2C is skew-symmetric; Mdot from dual numbers
        links = algorithms.chain(model)
        cs = [(x,) if link.prismatic else (math.cos(x), math.sin(x)) for link, x in zip(links, q)]
        dM = algorithms.crba(links, dual_angles(cs))
        Mdot = np.array(
            [
                [sum(partial(dM[i][j], k) * qd[k] for k in range(model.n)) for j in range(model.n)]
                for i in range(model.n)
            ]
        )
        assert_close(Mdot - 2 * C, -(Mdot - 2 * C).T, 1e-12)


def test_regressor_momentum_and_kinematics(case):
    _, loaded, pinocchio, rng = case
    model = loaded.model
    pi = inertial_parameters(model)
    links = algorithms.chain(model)
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1, 1, model.n) for _ in range(3))
        assert_close(regressor(model, q, qd, qdd) @ pi, rnea(model, q, qd, qdd))
        cs = [(x,) if link.prismatic else (math.cos(x), math.sin(x)) for link, x in zip(links, q)]
        p, dT = np.split(np.array(momentum_terms(links, cs, qd)), 2)
        assert_close(p, mass_matrix(model, q) @ qd)
        assert_close(dT, energy_gradient(links, cs, qd))
        pm, data = pinocchio.model, pinocchio.data
        pq = pinocchio.state(q)[0]
        pin.framesForwardKinematics(pm, data, pq)
        tip = data.oMf[pm.getFrameId("tip", pin.BODY)]
        base = data.oMf[pm.getFrameId("base", pin.BODY)]
        assert_close(flange_pose(model, q), (base.inverse() * tip).homogeneous, 1e-12)
        J = pin.computeFrameJacobian(pm, data, pq, pm.getFrameId("tip", pin.BODY), pin.LOCAL)[:, pinocchio.index]
        ours = flange_jacobian(model, q)  # base frame, (v; w) of the tip's origin
        R = (base.inverse() * tip).rotation
        assert_close(np.vstack([R.T @ ours[:3], R.T @ ours[3:]]), J, 1e-12)
    Y = regressor_batch(model, *(rng.uniform(-1, 1, (3, model.n)) for _ in range(3)))
    assert Y.shape == (3, model.n, 13 * model.n)


def test_the_parameter_form_and_the_exported_urdf_give_the_model_back(case):
    _, loaded, _, rng = case
    model = loaded.model
    again = RobotModel.from_params(model.to_params())
    assert again == model
    exported = load_urdf(export_urdf(model), tip_link="flange").model
    q, qd, qdd = (rng.uniform(-1, 1, model.n) for _ in range(3))
    assert [j.kind for j in exported.joints] == [j.kind for j in model.joints]
    assert exported.joint_names == model.joint_names
    assert_close(rnea(exported.with_gravity(model.gravity), q, qd, qdd), rnea(model, q, qd, qdd), 1e-12)


def test_the_payload_check_proves_its_bounds_for_prismatic_joints_too(case):
    """The worst static torques' proven bounds hold above every sampled pose's torques, and
    the torques found at real poses, whatever the joints' kinds."""
    _, loaded, _, rng = case
    model = loaded.model
    check = check_payload(model, RigidBody(0.1), rated_payload=RigidBody(1.0))
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    Q = lower + rng.random((3000, model.n)) * (upper - lower)
    sampled = np.abs(gravity_batch(model.with_payload(RigidBody(0.1)), Q)).max(axis=0)
    bound = check.workspace.bound
    assert (sampled <= bound * (1 + 1e-9) + 1e-12).all(), (sampled, bound)
    assert (np.abs(check.workspace.torque) <= bound * (1 + 1e-9) + 1e-12).all()
    assert (check.workspace.gap <= 1e-6 * max(1.0, bound.max())).all(), check.report()  # tight: the proof closed


def test_gravity_is_the_roots_minus_z_in_the_base_frame():
    rng = np.random.default_rng(5)
    text = chain_urdf(rng, ["revolute", "revolute", "revolute"])
    loaded = load_urdf(text, "base", "tip")
    pinocchio = Pinocchio(text, loaded.model.joint_names)
    base = pin.framesForwardKinematics(pinocchio.model, pinocchio.data, pin.neutral(pinocchio.model))
    base = pinocchio.data.oMf[pinocchio.model.getFrameId("base")]
    assert_close(loaded.model.gravity, base.rotation.T @ np.array([0.0, 0.0, -9.81]), 1e-14)
    assert abs(loaded.model.gravity[2]) < 9.8  # the base is turned: not the plain -z

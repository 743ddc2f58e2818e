"""The derivatives of the dynamics (rnea_derivatives, forward_dynamics_derivatives) and
M^-1 against Pinocchio's (computeRNEADerivatives, computeABADerivatives, computeMinverse)
and against central finite differences of the package's own rnea and forward_dynamics.

Pinocchio has no joint friction: its side gets the friction's own derivatives, written
here from the friction law (tau_f,i = v_i qd_i + c_i tanh(qd_i / v_s)), and its forward
dynamics runs on tau - tau_f(qd). Armature is on both sides. 1e-9 relative to the largest
entry of Pinocchio's matrix, on the IRB-140, random DH and URDF-form chains (armature and
friction), URDF chains with prismatic and continuous joints, and the chains of
example-robot-data that the corpus test compares.
"""

import math
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import (
    ModelError,
    RigidBody,
    forward_dynamics,
    forward_dynamics_batch,
    forward_dynamics_derivatives,
    inverse_mass_matrix,
    irb140,
    mass_matrix,
    rnea,
    rnea_derivatives,
)
from irb140_dynamics.core.algorithms import analytical_derivatives, derivatives
from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.urdf import load_urdf

from ..support import pinocchio_model
from ..support.common import full_sweep, loaded_irb140, random_model, random_urdf_model
from ..support.paths import URDF_DATA
from ..support.pinocchio_trees import pinocchio_state
from ..support.two_arms import TWO_ARMS, _joint, _link
from .test_urdf_any_chain import KINDS, chain_urdf
from .test_urdf_corpus import FILES, chains

RTOL = 1e-9  # relative to the largest entry of Pinocchio's matrix
FD_RTOL = 1e-6  # against central differences (step FD_STEP): their truncation and rounding
FD_STEP = 1e-6
STATES = 3
FLOOR = 1e-3  # the scale of a matrix that is zero (d tau / dqd of one joint): 1e-12 absolute

MODELS = {
    "irb140": irb140,
    "irb140_offset_payload": loaded_irb140,
    **{f"random_n{n}": (lambda n=n: random_model(np.random.default_rng(300 + n), n)) for n in (1, 3, 6, 7)},
    **{
        f"urdf_form_friction_n{n}": (lambda n=n: random_urdf_model(np.random.default_rng(400 + n), n, friction=True))
        for n in (2, 6)
    },
}


class Reference:
    """Pinocchio's derivatives of a chain, with the chain's friction added: ``model`` the
    Pinocchio model of the chain alone (in our joint order: ``index``), ``to_pin`` q as its
    configuration; viscous, Coulomb and the smoothing velocity per joint of the chain."""

    def __init__(self, model, to_pin, index, viscous, coulomb, smoothing):
        self.model, self.data = model, model.createData()
        self.to_pin, self.index = to_pin, np.array(index)
        self.viscous, self.coulomb, self.smoothing = np.asarray(viscous), np.asarray(coulomb), smoothing

    def _ours(self, matrix) -> np.ndarray:
        return np.array(matrix)[np.ix_(self.index, self.index)]

    def _full(self, x) -> np.ndarray:
        v = np.zeros(self.model.nv)
        v[self.index] = x
        return v

    def friction(self, qd):
        """(torques, slopes d tau_f / d qd) of the friction law at qd."""
        shape = np.tanh(qd / self.smoothing)
        return self.viscous * qd + self.coulomb * shape, self.viscous + self.coulomb * (1 - shape**2) / self.smoothing

    def rnea_derivatives(self, q, qd, qdd):
        dq, dqd, M = (
            self._ours(x)
            for x in pin.computeRNEADerivatives(self.model, self.data, self.to_pin(q), self._full(qd), self._full(qdd))
        )
        M = np.triu(M) + np.triu(M, 1).T
        return dq, dqd + np.diag(self.friction(qd)[1]), M

    def forward_dynamics_derivatives(self, q, qd, tau):
        torques, slopes = self.friction(qd)
        dq, dqd, Minv = (
            self._ours(x)
            for x in pin.computeABADerivatives(
                self.model, self.data, self.to_pin(q), self._full(qd), self._full(tau - torques)
            )
        )
        Minv = np.triu(Minv) + np.triu(Minv, 1).T
        return dq, dqd - Minv @ np.diag(slopes), Minv

    def inverse_mass_matrix(self, q):
        Minv = self._ours(pin.computeMinverse(self.model, self.data, self.to_pin(q)))
        return np.triu(Minv) + np.triu(Minv, 1).T


def of_robot_model(robot) -> Reference:
    """The reference for a RobotModel, Pinocchio's model built from its joints
    (support.pinocchio_model)."""
    friction = [(j.friction.viscous, j.friction.coulomb) for j in robot.joints]
    viscous, coulomb = zip(*friction)
    return Reference(
        pinocchio_model.build(robot),
        lambda q: np.asarray(q),
        range(robot.n),
        viscous,
        coulomb,
        robot.smoothing_velocity,
    )


def of_urdf(text: str, model, held=()) -> Reference:
    """The reference for a chain loaded from ``text``: Pinocchio's reading of the text, the
    joints off the chain locked where the model holds them (``held``: a LoadedUrdf's
    ``held_positions``; the rest at zero); its friction from Pinocchio's damping and friction."""
    full = pin.buildModelFromXML(text)
    names = model.joint_names
    counts = Counter(frame.name for frame in full.frames)
    for k, frame in enumerate(full.frames):  # buildReducedModel finds frames by name: one each
        if counts[frame.name] > 1 and frame.type != pin.FrameType.JOINT:
            frame.name += f"#{k}"
    kept = {full.getJointId(name) for name in names}
    locked = [j for j in range(1, full.njoints) if j not in kept]
    reduced = pin.buildReducedModel(full, locked, pinocchio_state(full, [], [], [], [], held)[0]) if locked else full
    reduced.gravity.linear = full.gravity.linear
    joints = [reduced.joints[reduced.getJointId(name)] for name in names]
    index = [j.idx_v for j in joints]
    assert sorted(index) == list(range(reduced.nv)) == list(range(model.n))

    def to_pin(q):
        pq = pin.neutral(reduced)
        for joint, x in zip(joints, q):
            if joint.nq == 2:  # continuous: (cos, sin)
                pq[joint.idx_q : joint.idx_q + 2] = math.cos(x), math.sin(x)
            else:
                pq[joint.idx_q] = x
        return pq

    viscous = [full.damping[full.joints[full.getJointId(name)].idx_v] for name in names]
    coulomb = [full.friction[full.joints[full.getJointId(name)].idx_v] for name in names]
    return Reference(reduced, to_pin, index, viscous, coulomb, model.smoothing_velocity)


def assert_agree(ours, theirs, rtol=RTOL, what=""):
    theirs = np.asarray(theirs)
    scale = max(np.max(np.abs(theirs)), FLOOR)
    error = np.max(np.abs(np.asarray(ours) - theirs)) / scale
    assert error <= rtol, f"{what}: {error:.2e} relative to the largest entry {scale:.3g}"


def random_state(rng, n):
    """q, qd, qdd, tau; the first joint slow, where Coulomb friction's slope is steep."""
    qd = rng.uniform(-2.0, 2.0, n)
    qd[0] = rng.uniform(-0.02, 0.02)
    return rng.uniform(-1.5, 1.5, n), qd, rng.uniform(-4.0, 4.0, n), rng.uniform(-30, 30, n)


def compare(model, reference: Reference, rng, states=STATES, label=""):
    """Our three functions against the reference at ``states`` random states. A chain whose
    M is singular (a last link without inertia) has no forward dynamics: refused."""
    for _ in range(states):
        q, qd, qdd, tau = random_state(rng, model.n)
        ours = rnea_derivatives(model, q, qd, qdd)
        M = ours[2]  # mass_matrix's (test_identities_of_the_matrices)
        singular = np.linalg.eigvalsh(M)[0] <= 1e-12 * np.abs(M).max()
        cases = [("rnea_derivatives", ours, reference.rnea_derivatives(q, qd, qdd))]
        if singular:
            with pytest.raises(ValueError, match="singular.*no inverse"):
                forward_dynamics_derivatives(model, q, qd, tau)
            with pytest.raises(ValueError, match="singular.*no inverse"):
                inverse_mass_matrix(model, q)
        else:
            ours = forward_dynamics_derivatives(model, q, qd, tau)
            cases.append(("forward_dynamics_derivatives", ours, reference.forward_dynamics_derivatives(q, qd, tau)))
            assert_agree(inverse_mass_matrix(model, q), reference.inverse_mass_matrix(q), what=f"{label} M^-1")
        for name, ours, theirs in cases:
            for part, x, y in zip(("d/dq", "d/dqd", "matrix"), ours, theirs):
                assert np.shape(x) == (model.n, model.n)
                assert_agree(x, y, what=f"{label} {name} {part}")


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def robot(request):
    return MODELS[request.param]()


def test_agree_with_pinocchio(robot):
    compare(robot, of_robot_model(robot), np.random.default_rng(5), label=robot.joint_names[0])


def test_the_friction_is_there_to_be_derived():
    robot = MODELS["urdf_form_friction_n2"]()
    assert robot.friction is not None and robot.friction.coulomb.all() and robot.friction.viscous.all()


@pytest.mark.parametrize("kinds", list(KINDS), ids=list(KINDS))
def test_urdf_chains_with_prismatic_and_continuous_joints_agree_with_pinocchio(kinds):
    rng = np.random.default_rng(sorted(KINDS).index(kinds) + 61)
    text = chain_urdf(rng, KINDS[kinds])
    model = load_urdf(text, "base", "tip").model
    assert [j.kind for j in model.joints].count("prismatic") == KINDS[kinds].count("prismatic")
    compare(model, of_urdf(text, model), rng, label=kinds)


def _tree(torso_turns: bool) -> str:
    """TWO_ARMS (support.two_arms) with its fingers as joints of their own (no mimic): a
    torso turning with two arms on it, or (``torso_turns`` False) held, so that each arm
    hangs from the base."""
    text = TWO_ARMS.replace('<mimic joint="r2" multiplier="-0.5" offset="0.01"/>', "")
    text = text.replace('<mimic joint="r2" multiplier="2.0" offset="0.2"/>', "")
    return (
        text
        if torso_turns
        else text.replace('<joint name="torso" type="revolute">', '<joint name="torso" type="fixed">')
    )


@pytest.mark.parametrize("torso_turns", [True, False], ids=["on a turning torso", "from the base"])
def test_trees_agree_with_pinocchio(torso_turns):
    """A whole tree's derivatives (closed forms on its branches, in the base frame), a
    prismatic finger and its damping included."""
    text = _tree(torso_turns)
    model = load_urdf(text).model
    assert model.mimics is None and any(link.parent is not None for link in algorithms.chain(model))
    assert [p < 0 for p in model.parent].count(True) == (1 if torso_turns else 2)
    compare(model, of_urdf(text, model), np.random.default_rng(63 + torso_turns), label="tree")


@pytest.mark.slow
@pytest.mark.skipif(not FILES, reason="example-robot-data is not installed")
def test_chains_of_example_robot_data_agree_with_pinocchio():
    """Every file's chains that load: one (seeded) per file in the suite, the first to load
    of its chains in a seeded order, all with IRB140_SWEEP=full, as the corpus test compares
    rnea, gravity and M (which loads every chain)."""
    rng = np.random.default_rng(42)
    compared = 0
    for path in FILES:
        text = Path(path).read_text()
        candidates = chains(text)
        if not full_sweep():
            candidates = [candidates[k] for k in rng.permutation(len(candidates))]
        loaded = []
        for base, tip in candidates:
            try:
                chain = load_urdf(text, base, tip)
                model = chain.model
            except ModelError as refusal:  # mimic joints: the corpus test checks the refusals
                assert "mimic" in str(refusal)
                continue
            if model.mimics is None:  # with mimic joints the derivatives are refused (test_urdf_trees)
                loaded.append((model, chain.held_positions))
                if not full_sweep():
                    break
        for model, held in loaded:
            compare(model, of_urdf(text, model, held), rng, states=1, label=f"{path.split('/robots/')[-1]}")
            compared += 1
    assert compared >= 50


# -- against central finite differences of the package's own functions ---------------------


def central_differences(f, x, step=FD_STEP):
    """d f / dx (columns by input) by central differences."""
    columns = []
    for j in range(len(x)):
        dx = np.zeros(len(x))
        dx[j] = step
        columns.append((f(x + dx) - f(x - dx)) / (2 * step))
    return np.array(columns).T


@pytest.mark.parametrize(
    "make", [irb140, MODELS["urdf_form_friction_n6"], MODELS["random_n7"]], ids=["irb140", "friction", "n7"]
)
def test_agree_with_finite_differences_of_rnea_and_forward_dynamics(make):
    model = make()
    rng = np.random.default_rng(17)
    for _ in range(STATES):
        q, qd, qdd, tau = random_state(rng, model.n)
        dq, dqd, M = rnea_derivatives(model, q, qd, qdd)
        assert_agree(dq, central_differences(lambda x: rnea(model, x, qd, qdd), q), FD_RTOL, "dtau/dq")
        assert_agree(dqd, central_differences(lambda x: rnea(model, q, x, qdd), qd), FD_RTOL, "dtau/dqd")
        assert_agree(M, central_differences(lambda x: rnea(model, q, qd, x), qdd), FD_RTOL, "M")
        A, B, Minv = forward_dynamics_derivatives(model, q, qd, tau)
        assert_agree(A, central_differences(lambda x: forward_dynamics(model, x, qd, tau), q), FD_RTOL, "dqdd/dq")
        assert_agree(B, central_differences(lambda x: forward_dynamics(model, q, x, tau), qd), FD_RTOL, "dqdd/dqd")
        assert_agree(Minv, central_differences(lambda x: forward_dynamics(model, q, qd, x), tau), FD_RTOL, "M^-1")


def test_identities_of_the_matrices():
    """M from rnea_derivatives is mass_matrix; M^-1 is its inverse, symmetric, the same from
    forward_dynamics_derivatives; qdd's derivatives are -M^-1 times tau's at FD's qdd."""
    model = MODELS["urdf_form_friction_n6"]()
    rng = np.random.default_rng(8)
    q, qd, _, tau = random_state(rng, model.n)
    qdd = forward_dynamics(model, q, qd, tau)
    dq, dqd, M = rnea_derivatives(model, q, qd, qdd)
    A, B, Minv = forward_dynamics_derivatives(model, q, qd, tau)
    assert_agree(M, mass_matrix(model, q), 1e-14)
    assert np.array_equal(Minv, Minv.T)
    assert_agree(Minv, inverse_mass_matrix(model, q), 1e-13)
    assert_agree(Minv @ M, np.eye(model.n), 1e-12)
    assert_agree(A, -Minv @ dq, 1e-9)
    assert_agree(B, -Minv @ dqd, 1e-9)


def test_bad_input_is_refused_naming_the_argument():
    model = irb140()
    zeros = np.zeros(6)
    with pytest.raises(ValueError, match="^q: expected 6 values"):
        rnea_derivatives(model, np.zeros(5), zeros, zeros)
    with pytest.raises(ValueError, match="^tau: must be finite"):
        forward_dynamics_derivatives(model, zeros, zeros, [0, 0, float("nan"), 0, 0, 0])
    with pytest.raises(ValueError, match="^q: expected"):
        inverse_mass_matrix(model, "q")
    with pytest.raises(ValueError, match="not finite.*too large"):
        rnea_derivatives(model, zeros, np.full(6, 1e200), zeros)


@pytest.mark.parametrize("arm", ["irb140", "ur5"])
def test_a_joint_moving_no_inertia_has_no_forward_dynamics_at_any_q(arm):
    """The last link massless, a point payload on its axis: M is singular for every q. The
    forward dynamics, its derivatives and M^-1 are refused, not numbers of 1e16 (M in
    another frame than the joints' keeps a rounding residue where its pivot is 0)."""
    if arm == "irb140":
        model = irb140(payload=RigidBody(2.0))
    else:
        model = load_urdf((URDF_DATA / "ur5.urdf").read_text(), tip_link="tool0").model.with_payload(RigidBody(2.0))
    model = replace(model, joints=(*model.joints[:-1], replace(model.joints[-1], link=RigidBody())))
    q, zeros = np.linspace(0.1, 0.6, model.n), np.zeros(model.n)
    assert mass_matrix(model, q)[-1, -1] == 0.0
    for call in (
        lambda: forward_dynamics_derivatives(model, q, zeros, zeros),
        lambda: inverse_mass_matrix(model, q),
        lambda: forward_dynamics(model, q, zeros, zeros),
        lambda: forward_dynamics_batch(model, q[None], zeros[None], zeros[None]),
    ):
        with pytest.raises(ValueError, match="singular.*no inverse"):
            call()


# -- the closed forms against their definition -----------------------------------------------


THREE_BRANCHES = f"""<robot name="three_branches"><link name="base"/>
  {_joint("slide", "base", "s1", kind="prismatic", axis="1 0 0")}{_link("s1")}
  {_joint("s2", "s1", "s2")}{_link("s2")}
  {_joint("a1", "base", "a1", axis="0 0 1")}{_link("a1")}
  {_joint("a2", "a1", "a2", axis="1 0 0")}{_link("a2")}
  {_joint("a3", "a1", "a3")}{_link("a3")}
  {_joint("b1", "base", "b1", axis="1 0 0")}{_link("b1")}
</robot>"""


def test_closed_forms_on_a_tree_are_the_recursions_on_dual_numbers():
    """Three branches from the base, one sliding, one forking: the closed forms (each
    subtree in its first link's frame) equal rnea's on dual numbers, and the forward
    dynamics' -M^-1 times them; a chain's reference (a link's frame) is refused."""
    model = load_urdf(THREE_BRANCHES).model
    links, n = algorithms.chain(model), model.n
    roots = [link for link, p in zip(links, model.parent) if p < 0]
    assert len(roots) == 3 and any(link.prismatic for link in roots)
    rng = np.random.default_rng(95)
    for _ in range(3):
        q, qd, qdd, tau = (x.tolist() for x in random_state(rng, n))
        cs = [(x,) if link.prismatic else (math.cos(x), math.sin(x)) for link, x in zip(links, q)]
        slopes, torques = rng.uniform(0.0, 2.0, n).tolist(), rng.uniform(-1.0, 1.0, n).tolist()
        dq, dqd = derivatives.rnea_partials(links, cs, qd, qdd, model.gravity, slopes)
        ours = analytical_derivatives.rnea_partials(links, cs, qd, qdd, model.gravity, slopes)
        for x, y in zip(ours, (dq, dqd, mass_matrix(model, q))):
            assert_agree(x, y, 1e-12, "tree")
        qdd_fd, _, Minv = derivatives.forward_dynamics(links, cs, qd, tau, model.gravity, torques)
        fd_dq, fd_dqd = derivatives.rnea_partials(links, cs, qd, qdd_fd, model.gravity, slopes)
        ours = analytical_derivatives.forward_dynamics_partials(links, cs, qd, tau, model.gravity, (torques, slopes))
        for x, y in zip(ours, (-np.array(Minv) @ fd_dq, -np.array(Minv) @ fd_dqd, Minv)):
            assert_agree(x, y, 1e-10, "tree, forward")
    with pytest.raises(ValueError, match="reference -1"):
        analytical_derivatives.rnea_partials(links, cs, qd, qdd, model.gravity, reference=0)


@pytest.mark.parametrize("kinds", list(KINDS), ids=list(KINDS))
def test_closed_forms_are_the_recursions_on_dual_numbers_in_any_frame(kinds):
    """The analytical derivatives (in the frame of any link: the kernels take link 0's or
    1's) equal rnea's on dual numbers, and the forward dynamics' -M^-1 times them at FD's
    qdd, friction slopes included."""
    rng = np.random.default_rng(sorted(KINDS).index(kinds) + 90)
    model = load_urdf(chain_urdf(rng, KINDS[kinds]), "base", "tip").model
    links, n = algorithms.chain(model), model.n
    for _ in range(3):
        q, qd, qdd, tau = (x.tolist() for x in random_state(rng, n))
        cs = [(x,) if link.prismatic else (math.cos(x), math.sin(x)) for link, x in zip(links, q)]
        slopes = rng.uniform(0.0, 2.0, n).tolist()
        torques = rng.uniform(-1.0, 1.0, n).tolist()
        dq, dqd = derivatives.rnea_partials(links, cs, qd, qdd, model.gravity, slopes)
        qdd_fd, _, Minv = derivatives.forward_dynamics(links, cs, qd, tau, model.gravity, torques)
        fd_dq, fd_dqd = derivatives.rnea_partials(links, cs, qd, qdd_fd, model.gravity, slopes)
        for r in range(n):
            ours = analytical_derivatives.rnea_partials(links, cs, qd, qdd, model.gravity, slopes, r)
            for x, y in zip(ours, (dq, dqd, mass_matrix(model, q))):
                assert_agree(x, y, 1e-12, f"{kinds} frame {r}")
            ours = analytical_derivatives.forward_dynamics_partials(
                links, cs, qd, tau, model.gravity, (torques, slopes), r
            )
            want = (-np.array(Minv) @ fd_dq, -np.array(Minv) @ fd_dqd, Minv)
            for x, y in zip(ours, want):
                assert_agree(x, y, 1e-10, f"{kinds} forward, frame {r}")

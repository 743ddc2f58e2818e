"""Pinocchio's rnea, gravity and M of a URDF's tree or chain, for a RobotModel read from it.

Pinocchio (buildModelFromXML) reads the whole URDF; the model's joints are found in it by
name, the others held at zero. With mimic joints, Pinocchio's own ``mimic=True`` model when
it builds it; where it refuses (a mimic joint before the joint it follows in the file),
its model with the mimic joints as joints of their own, projected by virtual work:
tau = G^T tau_all(G qd, G qdd), M = G^T M_all G. A fresh Data per call (Pinocchio's mimic
mass matrix is wrong with a Data reused).
"""

import importlib.metadata
import math

import numpy as np
import pinocchio as pin


def pinocchio_of(text: str, mimic: bool) -> tuple[pin.Model, bool]:
    """(Pinocchio's model of the URDF, whether it follows the mimic joints itself)."""
    if mimic:
        try:
            return pin.buildModelFromXML(text, mimic=True), True
        except ValueError:  # "The parent joint of the mimic joint is not in the kinematic tree"
            pass
    return pin.buildModelFromXML(text), False


def corpus_files() -> list[str]:
    """The URDF files of example-robot-data (none when it is not installed)."""
    try:
        distribution = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return []
    return sorted(str(distribution.locate_file(f)) for f in distribution.files or () if str(f).endswith(".urdf"))


def pinocchio_state(full: pin.Model, names, q, qd, qdd, held=None):
    """Pinocchio's q, v, a: the named joints at q, qd, qdd, the joints ``held`` at its
    positions (a LoadedUrdf's ``held_positions``; a mimic joint of Pinocchio's ``mimic=True``
    model follows its joint there), the others at zero."""
    pq, v, a = pin.neutral(full), np.zeros(full.nv), np.zeros(full.nv)
    held = dict(held or {})
    rest = [name for name in held if full.joints[full.getJointId(name)].nq > 0]
    for name, x, xd, xdd in zip([*rest, *names], [*(held[n] for n in rest), *q], [0.0] * len(rest) + [*qd],
                                [0.0] * len(rest) + [*qdd]):  # fmt: skip
        joint = full.joints[full.getJointId(name)]
        if joint.nq == 2:  # continuous: (cos, sin)
            pq[joint.idx_q : joint.idx_q + 2] = math.cos(x), math.sin(x)
        else:
            pq[joint.idx_q] = x
        v[joint.idx_v], a[joint.idx_v] = xd, xdd
    return pq, v, a


def reference(full: pin.Model, follows_mimics: bool, model, q, qd, qdd, held=None):
    """Pinocchio's (tau without friction, g, M) of ``model`` at (q, qd, qdd), the joints
    ``held`` at its positions (``pinocchio_state``)."""
    if model.mimics is None or follows_mimics:
        names, G = model.joint_names, np.eye(model.n)
        state = q, qd, qdd
    else:
        names, G = [j.name for j in model.joints], model.mimic_matrix()
        state = model.all_positions(q), G @ qd, G @ qdd
    index = [full.joints[full.getJointId(name)].idx_v for name in names]
    pq, v, a = pinocchio_state(full, names, *state, held=held)
    tau = pin.rnea(full, full.createData(), pq, v, a)[index]
    g = pin.computeGeneralizedGravity(full, full.createData(), pq)[index]
    M = pin.crba(full, full.createData(), pq)
    M = (np.triu(M) + np.triu(M, 1).T)[np.ix_(index, index)]
    return G.T @ tau, G.T @ g, G.T @ M @ G


def worst_error(text: str, model, rng, states: int, held=None) -> float:
    """The largest difference of rnea (friction taken out), gravity and M from Pinocchio's
    over ``states`` random states, relative to the largest of Pinocchio's (at least 1); the
    joints ``held`` at its positions (a LoadedUrdf's ``held_positions``)."""
    from irb140_dynamics.core import gravity, mass_matrix, rnea

    full, follows = pinocchio_of(text, model.mimics is not None)
    worst = 0.0
    for _ in range(states):
        q, qd, qdd = rng.uniform(-1.5, 1.5, model.n), rng.uniform(-2, 2, model.n), rng.uniform(-3, 3, model.n)
        tau, g, M = reference(full, follows, model, q, qd, qdd, held)
        friction = 0.0 if model.friction is None else model.friction.torques(qd)
        for ours, theirs in (
            (rnea(model, q, qd, qdd) - friction, tau),
            (gravity(model, q), g),
            (mass_matrix(model, q), M),
        ):
            worst = max(worst, float(np.max(np.abs(ours - theirs)) / max(1.0, np.max(np.abs(theirs)))))
    return worst

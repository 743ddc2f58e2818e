"""Shared test helpers: seeded random models and states, and a norm-wise closeness check."""

import math
import os

import numpy as np
import yaml

from irb140_dynamics.core import DH, Friction, Joint, Placement, RigidBody, RobotModel, irb140

RIGHT_ANGLES = (0.0, math.pi / 2, -math.pi / 2, math.pi)

# A payload with its CoM off the flange axis and a full (non-diagonal) inertia tensor.
OFFSET_PAYLOAD = RigidBody(
    mass=4.5,
    com=(0.03, -0.02, 0.08),
    inertia=(0.021, 0.026, 0.017, 0.0021, -0.0013, 0.0032),
)


def load_yaml(text: str):
    """The YAML document of ``text`` by PyYAML's safe loader, libyaml's where PyYAML has it
    (the same document, 20x faster on a trajectory file of thousands of points)."""
    return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def full_sweep() -> bool:
    """Whether sweep tests run every seeded case (IRB140_SWEEP=full, docs/development.md)."""
    return os.environ.get("IRB140_SWEEP") == "full"


def sweep(quick: int, full: int) -> int:
    """How many seeded cases a sweep test runs: ``quick`` in the suite, ``full`` with
    IRB140_SWEEP=full; the quick ones are the first of the full ones."""
    return full if full_sweep() else quick


def spread(cases: list, quick: int, key) -> list:
    """The cases a sweep test runs: all of ``cases`` with IRB140_SWEEP=full; in the suite,
    ``quick`` of them spread evenly over the range of ``key(case)`` (its least, its
    greatest and between: an early and a late moment, say), in the order of ``cases``."""
    if full_sweep() or len(cases) <= quick:
        return list(cases)
    order = sorted(range(len(cases)), key=lambda k: key(cases[k]))
    chosen = {order[round(i * (len(cases) - 1) / (quick - 1))] for i in range(quick)}
    return [case for k, case in enumerate(cases) if k in chosen]


def loaded_irb140() -> RobotModel:
    return irb140(payload=OFFSET_PAYLOAD)


def model_makers(seed: int, sizes=(2, 7)) -> dict:
    """Model makers by name: the IRB-140, it with an offset payload, random models of ``sizes``."""
    models = {"irb140": irb140, "irb140_offset_payload": loaded_irb140}
    for n in sizes:
        models[f"random_n{n}"] = lambda n=n: random_model(np.random.default_rng(seed + n), n)
    return models


def random_rotation(rng) -> np.ndarray:
    """A random proper rotation matrix."""
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


def random_inertia(rng, mass: float, size: float = 0.2) -> tuple:
    """A physically valid inertia about the CoM: I = R (tr(S) 1 - S) R^T, S the second moments."""
    S = np.diag(mass * size**2 * rng.uniform(0.01, 1.0, 3))
    R = random_rotation(rng)
    I = R @ (np.trace(S) * np.eye(3) - S) @ R.T
    return (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])


def random_body(rng) -> RigidBody:
    mass = rng.uniform(0.5, 10.0)
    return RigidBody(mass, tuple(rng.uniform(-0.3, 0.3, 3)), random_inertia(rng, mass))


def random_model(rng, n: int) -> RobotModel:
    """n revolute joints with random DH rows (about half the angles exact right angles),
    random link inertials and payload, and gravity in a random direction."""

    def angle():
        return float(rng.choice(RIGHT_ANGLES)) if rng.random() < 0.5 else rng.uniform(-math.pi, math.pi)

    joints = tuple(
        Joint(
            f"j{i}",
            DH(a=rng.uniform(-0.5, 0.5), alpha=angle(), d=rng.uniform(-0.5, 0.5), theta_offset=angle()),
            random_body(rng),
        )
        for i in range(n)
    )
    direction = rng.normal(size=3)
    gravity = tuple(9.81 * direction / np.linalg.norm(direction))
    return RobotModel(joints, gravity, random_body(rng))


def random_urdf_model(rng, n: int, friction: bool = False) -> RobotModel:
    """n revolute joints in URDF form: random origins (about half the rotations right
    angles), axes along x, y, z or anywhere, a random flange, armature (and friction)."""

    def angle():
        return float(rng.choice(RIGHT_ANGLES)) if rng.random() < 0.5 else rng.uniform(-math.pi, math.pi)

    def axis():
        if rng.random() < 0.5:
            return tuple(float(x) for x in np.eye(3)[rng.integers(3)] * rng.choice([-1.0, 1.0]))
        u = rng.normal(size=3)
        return tuple(u / np.linalg.norm(u))

    def placement():
        return Placement(tuple(rng.uniform(-0.4, 0.4, 3)), (angle(), angle(), angle()))

    joints = tuple(
        Joint(
            f"j{i}",
            link=random_body(rng),
            origin=placement(),
            axis=axis(),
            armature=rng.uniform(0.0, 0.5),
            friction=Friction(*rng.uniform(0.0, 2.0, 2)) if friction else Friction(),
        )
        for i in range(n)
    )
    direction = rng.normal(size=3)
    gravity = tuple(9.81 * direction / np.linalg.norm(direction))
    return RobotModel(joints, gravity, random_body(rng), flange=placement())


def random_states(rng, n: int, count: int):
    """(Q, QD, QDD), each shaped (count, n)."""
    Q = rng.uniform(-math.pi, math.pi, (count, n))
    QD = rng.uniform(-2.0, 2.0, (count, n))
    QDD = rng.uniform(-5.0, 5.0, (count, n))
    return Q, QD, QDD


def relative_error(actual, expected) -> float:
    """||actual - expected|| / ||expected|| (Frobenius norm for matrices)."""
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    return float(np.linalg.norm(actual - expected) / np.linalg.norm(expected))


def assert_close(actual, expected, rtol: float, atol: float = 0.0, what: str = "") -> None:
    """||actual - expected|| <= rtol ||expected|| + atol, the norms over the whole array."""
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} != {expected.shape}"
    error = np.linalg.norm(actual - expected)
    bound = rtol * np.linalg.norm(expected) + atol
    assert error <= bound, f"{what}: |error| {error:.3e} > {bound:.3e}\n{actual}\n!=\n{expected}"

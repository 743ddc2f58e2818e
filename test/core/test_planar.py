"""A 2-link planar arm against its textbook closed-form dynamics (nothing assumes 6 joints)."""

import math

import numpy as np
import pytest

from irb140_dynamics.core import DH, Joint, RigidBody, RobotModel, coriolis_matrix, gravity, mass_matrix, rnea

from ..support.common import assert_close, random_inertia, random_states

G0 = 9.81  # gravity (0, -G0, 0): in the plane of motion, along -y of the base


class PlanarArm:
    """Link i: length a_i, mass m_i, CoM lc_i from joint i along the link, inertia I_i about
    the CoM and the z axis (its other components are random and must not matter)."""

    def __init__(self, seed):
        rng = np.random.default_rng(seed)
        self.a = rng.uniform(0.2, 1.0, 2)
        self.m = rng.uniform(0.5, 5.0, 2)
        self.lc = self.a * rng.uniform(0.1, 0.9, 2)
        self.offset = rng.uniform(-math.pi, math.pi, 2)
        inertias = [random_inertia(rng, m) for m in self.m]
        self.I = np.array([inertia[2] for inertia in inertias])  # Izz
        joints = tuple(
            Joint(
                f"joint_{i + 1}",
                DH(a=self.a[i], alpha=0.0, d=0.0, theta_offset=self.offset[i]),
                # DH frame i sits at the far end of link i, x along the link
                RigidBody(self.m[i], (self.lc[i] - self.a[i], 0.0, rng.uniform(-0.1, 0.1)), inertias[i]),
            )
            for i in range(2)
        )
        self.model = RobotModel(joints, gravity=(0.0, -G0, 0.0))

    def mass_matrix(self, q):
        (a1, _), (m1, m2), (lc1, lc2), (I1, I2) = self.a, self.m, self.lc, self.I
        c2 = math.cos(q[1] + self.offset[1])
        m11 = m1 * lc1**2 + I1 + m2 * (a1**2 + lc2**2 + 2 * a1 * lc2 * c2) + I2
        m12 = m2 * (lc2**2 + a1 * lc2 * c2) + I2
        m22 = m2 * lc2**2 + I2
        return np.array([[m11, m12], [m12, m22]])

    def coriolis_matrix(self, q, qd):
        h = -self.m[1] * self.a[0] * self.lc[1] * math.sin(q[1] + self.offset[1])
        return np.array([[h * qd[1], h * (qd[0] + qd[1])], [-h * qd[0], 0.0]])

    def gravity(self, q):
        (a1, _), (m1, m2), (lc1, lc2) = self.a, self.m, self.lc
        theta1, theta12 = q[0] + self.offset[0], q[0] + q[1] + self.offset[0] + self.offset[1]
        g2 = m2 * lc2 * G0 * math.cos(theta12)
        return np.array([(m1 * lc1 + m2 * a1) * G0 * math.cos(theta1) + g2, g2])

    def torques(self, q, qd, qdd):
        return self.mass_matrix(q) @ qdd + self.coriolis_matrix(q, qd) @ qd + self.gravity(q)


@pytest.fixture(scope="module", params=[1, 2, 3])
def arm(request):
    return PlanarArm(seed=request.param)


@pytest.fixture
def states():
    return list(zip(*random_states(np.random.default_rng(23), 2, 200)))


RTOL = 1e-12


def test_torques(arm, states):
    for q, qd, qdd in states:
        assert_close(rnea(arm.model, q, qd, qdd), arm.torques(q, qd, qdd), RTOL, 1e-14, f"tau at q={q}")


def test_mass_matrix(arm, states):
    for q, _, _ in states:
        assert_close(mass_matrix(arm.model, q), arm.mass_matrix(q), RTOL, 0.0, f"M at q={q}")


def test_gravity(arm, states):
    for q, _, _ in states:
        assert_close(gravity(arm.model, q), arm.gravity(q), RTOL, 1e-14, f"g at q={q}")


def test_coriolis_matrix(arm, states):
    for q, qd, _ in states:
        assert_close(coriolis_matrix(arm.model, q, qd), arm.coriolis_matrix(q, qd), RTOL, 1e-14, f"C at q={q}")

"""The core's public API refuses what it should: a state is n finite real
numbers; anything else, and any result that would not be finite, is a ValueError naming
the argument; payload functions check their bodies and limits too."""

import math

import numpy as np
import pytest

from irb140_dynamics.core import (
    ModelError,
    RigidBody,
    check_payload,
    coriolis,
    coriolis_batch,
    coriolis_matrix,
    derive_torque_limits,
    flange_jacobian,
    flange_pose,
    forward_dynamics,
    forward_dynamics_batch,
    gravity,
    gravity_batch,
    irb140,
    link_frames,
    mass_matrix,
    max_payload_at,
    rnea,
    rnea_batch,
    workspace_load,
)
from irb140_dynamics.core.model.rigid_body import MAX_MASS
from irb140_dynamics.core.model.states import state

MODEL = irb140()
GOOD = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6]
STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]

# the classes of bad state: not a sequence of numbers, not real, booleans, wrong length
BAD_STATES = {
    "dict": {i: 0.0 for i in range(6)},
    "set": {0.0, 1.0, 2.0, 3.0, 4.0, 5.0},
    "str": "012345",
    "None": None,
    "number": 1.0,
    "complex": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6j],
    "complex array": np.zeros(6, dtype=complex),
    "bool": [True, False, 0.0, 0.0, 0.0, 0.0],
    "bool array": np.zeros(6, dtype=bool),
    "str values": ["0.1"] * 6,
    "None values": [None] * 6,
    "nested": [[0.0]] * 6,
    "2-D array": np.zeros((2, 3)),
    "too short": [0.0] * 5,
    "too long": np.zeros(7),
}

# each public function taking a state, with the name of the argument under test
CALLS = {
    "rnea q": ("q", lambda x: rnea(MODEL, x, GOOD, GOOD)),
    "rnea qd": ("qd", lambda x: rnea(MODEL, GOOD, x, GOOD)),
    "rnea qdd": ("qdd", lambda x: rnea(MODEL, GOOD, GOOD, x)),
    "rnea f_ext": ("f_ext", lambda x: rnea(MODEL, GOOD, GOOD, GOOD, x)),
    "gravity": ("q", lambda x: gravity(MODEL, x)),
    "coriolis": ("qd", lambda x: coriolis(MODEL, GOOD, x)),
    "coriolis_matrix": ("q", lambda x: coriolis_matrix(MODEL, x, GOOD)),
    "mass_matrix": ("q", lambda x: mass_matrix(MODEL, x)),
    "forward_dynamics": ("tau", lambda x: forward_dynamics(MODEL, GOOD, GOOD, x)),
    "flange_pose": ("q", lambda x: flange_pose(MODEL, x)),
    "flange_jacobian": ("q", lambda x: flange_jacobian(MODEL, x)),
    "link_frames": ("q", lambda x: link_frames(MODEL, x)),
    "max_payload_at q": ("q", lambda x: max_payload_at(MODEL, RigidBody(1.0), [300.0] * 6, x)),
    "max_payload_at qd": ("qd", lambda x: max_payload_at(MODEL, RigidBody(1.0), [300.0] * 6, GOOD, x)),
    "check_payload q": ("q", lambda x: check_payload(MODEL, RigidBody(1.0), q=x)),
    "check_payload qd": ("qd", lambda x: check_payload(MODEL, RigidBody(1.0), q=GOOD, qd=x)),
}


@pytest.mark.parametrize("call", CALLS)
@pytest.mark.parametrize("bad", BAD_STATES)
def test_a_bad_state_is_refused_naming_the_argument(call, bad):
    name, function = CALLS[call]
    value = BAD_STATES[bad]
    if bad == "None" and (name in ("f_ext", "qd") or call == "check_payload q"):
        return  # None there means none given: no wrench, qd = 0, no state
    if name == "f_ext" and bad == "too short":
        value = [0.0] * 5  # six values expected there
    with pytest.raises(ValueError, match=f"^{name}: "):
        function(value)


@pytest.mark.parametrize(
    "x",
    [
        GOOD,
        tuple(GOOD),
        np.array(GOOD),
        np.array(GOOD, dtype=np.float32),
        [0, 1, 2, 3, 4, 5],
        np.arange(6),
        [np.float64(v) for v in GOOD],
        [np.int32(1)] * 6,
        range(6),
    ],
    ids=["list", "tuple", "array", "float32", "ints", "int array", "numpy floats", "numpy ints", "range"],
)
def test_real_sequences_are_states(x):
    expected = rnea(MODEL, [float(v) for v in x], GOOD, GOOD)
    np.testing.assert_array_equal(rnea(MODEL, x, GOOD, GOOD), expected)
    assert list(state(x, 6, "q")) == [float(v) for v in x]


def test_batch_states_are_real_numbers_too():
    Q = np.zeros((4, 6))
    for name, bad in (
        ("Q", Q.astype(bool)),
        ("Q", Q.astype(complex)),
        ("Q", [["0"] * 6] * 4),
        ("Q", [[True] + [0.0] * 5] * 4),
        ("Q", {"a": 1}),
    ):
        with pytest.raises(ValueError, match=f"^{name}: "):
            gravity_batch(MODEL, bad)
    with pytest.raises(ValueError, match="^QD: "):
        rnea_batch(MODEL, Q, Q.astype(bool), Q)
    np.testing.assert_array_equal(gravity_batch(MODEL, Q.tolist()), gravity_batch(MODEL, Q))


def test_a_result_that_would_not_be_finite_is_refused_naming_the_inputs():
    """Finite inputs so large that the torques overflow: ValueError, never inf or NaN."""
    huge = [1e200] * 6
    with pytest.raises(ValueError, match=r"^rnea: the result is not finite for q=\[.*\], qd=\[1e\+200.*qdd="):
        rnea(MODEL, GOOD, huge, GOOD)
    with pytest.raises(ValueError, match="^rnea: the result is not finite .*f_ext="):
        rnea(MODEL, GOOD, GOOD, [1e308] * 6, [0.0] * 6)
    with pytest.raises(ValueError, match="^coriolis: the result is not finite"):
        coriolis(MODEL, GOOD, huge)
    with pytest.raises(ValueError, match="^coriolis_matrix: the result is not finite"):
        coriolis_matrix(MODEL, GOOD, [1.7e308] * 6)  # linear in qd: only near the float limit
    with pytest.raises(ValueError, match="^forward_dynamics: the result is not finite"):
        forward_dynamics(MODEL, GOOD, huge, GOOD)
    Q = np.zeros((3, 6))
    QD = Q.copy()
    QD[1] = 1e200
    with pytest.raises(ValueError, match=r"^rnea_batch: the result is not finite at state 1 of Q, QD, QDD"):
        rnea_batch(MODEL, Q, QD, Q)
    with pytest.raises(ValueError, match="^coriolis_batch: the result is not finite at state 1"):
        coriolis_batch(MODEL, Q, QD)
    with pytest.raises(ValueError, match="^forward_dynamics_batch: the result is not finite at state 1"):
        forward_dynamics_batch(MODEL, Q, QD, Q)


# -- payload functions ------------------------------------------------------------------------------

BAD_MASSES = {
    "nan": math.nan,
    "inf": math.inf,
    "negative": -1.0,
    "beyond the cap": 1e300,
    "str": "1.0",
    "bool": True,
    "None": None,
}


@pytest.fixture(scope="module")
def limits():
    return derive_torque_limits(MODEL)


@pytest.mark.parametrize("bad", BAD_MASSES)
def test_payload_functions_refuse_a_bad_payload_mass_naming_it(bad, limits):
    body = RigidBody(BAD_MASSES[bad])
    calls = {
        "payload": [
            lambda: workspace_load(MODEL, body, limits),
            lambda: check_payload(MODEL, body, limits),
            lambda: max_payload_at(MODEL, body, limits, GOOD),
        ],
        "rated_payload": [
            lambda: derive_torque_limits(MODEL, body),
            lambda: check_payload(MODEL, RigidBody(1.0), rated_payload=body),
        ],
    }
    for name, functions in calls.items():
        for function in functions:
            with pytest.raises(ModelError, match=f"^{name}.mass: "):
                function()


def test_payload_functions_refuse_bad_shapes_and_non_bodies(limits):
    with pytest.raises(ModelError, match="^payload.com: must be finite"):
        workspace_load(MODEL, RigidBody(1.0, (math.nan, 0.0, 0.0)), limits)
    with pytest.raises(ModelError, match="^rated_payload.inertia: "):
        derive_torque_limits(MODEL, RigidBody(1.0, (0.0, 0.0, 0.0), (1.0, 1.0, 3.0, 0.0, 0.0, 0.0)))
    with pytest.raises(ModelError, match="^payload: expected a RigidBody, got 6.0"):
        check_payload(MODEL, 6.0)
    with pytest.raises(ModelError, match=r"^payload.mass: must be <= 1e\+06 kg"):
        max_payload_at(MODEL, RigidBody(2 * MAX_MASS), limits, GOOD)


@pytest.mark.parametrize("bad", [[math.nan] * 6, [-1.0] * 6, [300.0] * 5, "300", None, {"joint_1": 1.0}])
def test_payload_functions_refuse_bad_limits(bad):
    """A NaN limit would pass every payload."""
    with pytest.raises(ValueError, match="^limits: "):
        max_payload_at(MODEL, RigidBody(1.0), bad, GOOD)
    with pytest.raises(ValueError, match="^limits: "):
        workspace_load(MODEL, RigidBody(1.0), bad)


def test_infinite_limits_mean_none(limits):
    best = max_payload_at(MODEL, RigidBody(1.0), [math.inf] * 6, STRETCHED)
    assert best.mass == math.inf

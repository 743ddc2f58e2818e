"""Models that differ only in payload or gravity share their compiled kernels (the payload
and gravity are an argument, only their zeros folded), with the same numbers as ever."""

import threading

import numpy as np

from irb140_dynamics.core import RigidBody, RobotModel, gravity, irb140, mass_matrix, rnea
from irb140_dynamics.core.codegen import kernels as kernel_module
from irb140_dynamics.core.codegen.kernels import kernels_of

from ..support.common import OFFSET_PAYLOAD, random_model, random_states


def code(model, name="rnea"):
    return getattr(kernels_of(model), name).scalar.__code__


def test_a_payload_mass_or_gravity_change_shares_the_code():
    base = irb140()
    assert code(base) and code(base, "gravity_torques")
    for other in (
        irb140(payload=RigidBody(3.0)),
        irb140(payload=RigidBody(5.0, (0.0, 0.0, 0.1))),
        base.with_gravity((0.0, 0.0, -9.80665)),
    ):
        assert kernels_of(other).traced("rnea", "gravity_torques")  # by base, above
        assert code(other) is code(base) and code(other, "gravity_torques") is code(base, "gravity_torques")


def test_another_pattern_of_zeros_or_another_arm_compiles_its_own():
    base = irb140()
    assert code(irb140(payload=OFFSET_PAYLOAD)) is not code(base)  # off the flange axis: new nonzeros
    assert code(base.with_gravity((0.0, 1.0, -9.81))) is not code(base)
    heavier_link = irb140().to_params() | {"joint_2.link.mass": 30.0}
    assert code(RobotModel.from_params(heavier_link)) is not code(base)


def test_shared_code_gives_each_model_its_own_torques():
    """Numbers against a model compiled afresh (cache emptied), bit for bit."""
    rng = np.random.default_rng(5)
    arm = random_model(rng, 5)
    payloads = [RigidBody(m, (0.0, 0.0, 0.05)) for m in (0.5, 2.0, 7.0)]
    models = [arm.with_payload(p) for p in payloads] + [
        arm.with_payload(payloads[0]).with_gravity([0.4 * g for g in arm.gravity])
    ]
    Q, QD, QDD = random_states(rng, 5, 20)
    shared = [
        [(rnea(m, q, qd, qdd), gravity(m, q), mass_matrix(m, q)) for q, qd, qdd in zip(Q, QD, QDD)] for m in models
    ]
    assert len({code(m) for m in models}) == 1
    kernel_module._arm.cache_clear()
    for model, results in zip(models, shared):
        fresh = type(model)(model.joints, model.gravity, model.payload)  # new Kernels, new code
        for (q, qd, qdd), (tau, g, M) in zip(zip(Q, QD, QDD), results):
            assert rnea(fresh, q, qd, qdd).tolist() == tau.tolist()
            assert gravity(fresh, q).tolist() == g.tolist()
            assert mass_matrix(fresh, q).tolist() == M.tolist()
        kernel_module._arm.cache_clear()


def test_threads_asking_at_once_get_one_kernel():
    kernel_module._arm.cache_clear()
    model = irb140(payload=RigidBody(1.25, (0.0, 0.0, 0.02)))
    start, got = threading.Barrier(4), []

    def ask():
        start.wait()
        got.append(kernels_of(model).kernel("mass_matrix"))

    threads = [threading.Thread(target=ask) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=60.0)
    assert len(got) == 4 and all(kernel is got[0] for kernel in got)

"""Benchmark of the dynamics core against Pinocchio on the same IRB-140 model.

    .venv/bin/python bench/bench_core.py

Prints one table (ours, baseline, ratio ours/baseline, target) and writes the raw figures
to bench/results/core.json. Sections:

- single state: per-call cost of the public functions on NumPy (6,) arrays against
  Pinocchio's, with their kernels compiled as C (irb140_dynamics.native: what a program that
  calls them often gets); the kernels' Python form on Python lists; a textbook NumPy RNEA,
  the approach the generated code avoids.
- batch: states per second of the ``*_batch`` functions on N random states against a
  Python loop of the Pinocchio call over the same states.
- kernel generation: the one-off cost of tracing and compiling each kernel of a fresh model.
- URDF arms: the UR5 and the Panda of example-robot-data read by our URDF loader against
  Pinocchio's URDF parser on the same file, per call (rnea, gravity, mass matrix), with
  native kernels, then in the kernels' Python form (IRB140_NATIVE=0); and a whole tree,
  Baxter's two arms and head pan (15 joints).
- derivatives: rnea_derivatives, forward_dynamics_derivatives, inverse_mass_matrix against
  Pinocchio's computeRNEADerivatives, computeABADerivatives, computeMinverse on the same
  three arms, native, alternating blocks (derivatives_section).

Every pair is checked to give the same numbers before it is timed.
"""

from __future__ import annotations

import math
import os
import re
import time
import timeit
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
from common import (
    # first: puts the checkout on sys.path
    Figure,
    Row,
    Target,
    example_robot_urdf,
    machine_info,
    print_table,
    seconds_per_call,
    shown,
    write_results,
)
from derivatives_section import derivative_rows
from prepare_section import preparation

from irb140_dynamics.core import (
    gravity,
    gravity_batch,
    irb140,
    mass_matrix,
    mass_matrix_batch,
    prepare,
    rnea,
    rnea_batch,
)
from irb140_dynamics.core.codegen import kernels as kernel_cache  # noqa: E402
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.io.urdf import load_urdf  # noqa: E402
from irb140_dynamics.core.model.rigid_body import RigidBody, inertia_matrix  # noqa: E402
from test.support.pinocchio_model import build as pinocchio_model  # noqa: E402
from test.support.pinocchio_model import rot_x, rot_z

BATCH_STATES = 100_000
BATCH_CHECKED = 1_000  # states of the batch compared with Pinocchio
BATCH_REPEATS = 7
FRESH_MODELS = 3  # kernel generation is timed on this many fresh models
KERNELS = ("rnea", "rnea_wrench", "gravity_torques", "coriolis", "mass_matrix", "coriolis_matrix")
TOLERANCE = dict(rtol=1e-9, atol=1e-9)
SEED = 140
PAIRED_BLOCKS = 800  # alternating blocks of the URDF arms' timings
NATIVE_TARGET = 0.7  # ours / Pinocchio's per call, native, each arm and verb


# -- the baselines ----------------------------------------------------------------------


class TextbookRnea:
    """The textbook recursive Newton-Euler (Luh, Walker, Paul) on NumPy 3-vectors.

    Everything of link i in frame i; R_i = Rz(q_i + offset_i) Rx(alpha_i) turns frame i
    into frame i-1; p_i = o_{i-1} -> o_i and c_i = o_i -> centre of mass, in frame i.
    """

    def __init__(self, model):
        self.links = []
        for joint, body in zip(model.joints, model.bodies):
            a, alpha, d = joint.dh.a, joint.dh.alpha, joint.dh.d
            p = np.array([a, d * math.sin(alpha), d * math.cos(alpha)])
            self.links.append((joint.dh, p, body.mass, np.array(body.com), inertia_matrix(body.inertia)))
        self.gravity = np.array(model.gravity)

    def __call__(self, q, qd, qdd) -> np.ndarray:
        z = np.array([0.0, 0.0, 1.0])
        w, dw, a = np.zeros(3), np.zeros(3), -self.gravity
        forward = []
        for (dh, p, m, c, inertia), q_i, qd_i, qdd_i in zip(self.links, q, qd, qdd):
            R = rot_z(q_i + dh.theta_offset) @ rot_x(dh.alpha)
            dw = R.T @ (dw + z * qdd_i + np.cross(w, z * qd_i))
            w = R.T @ (w + z * qd_i)
            a = R.T @ a + np.cross(dw, p) + np.cross(w, np.cross(w, p))
            a_com = a + np.cross(dw, c) + np.cross(w, np.cross(w, c))
            force, moment = m * a_com, inertia @ dw + np.cross(w, inertia @ w)
            forward.append((R, p, c, force, moment))

        tau = np.empty(len(self.links))
        f, n, R_child = np.zeros(3), np.zeros(3), np.eye(3)
        for i in reversed(range(len(self.links))):
            R, p, c, force, moment = forward[i]
            f_child, n_child = R_child @ f, R_child @ n
            f = f_child + force
            n = n_child + np.cross(p, f_child) + np.cross(p + c, force) + moment
            tau[i] = n @ (R.T @ z)
            R_child = R
        return tau


# -- the benchmarks -----------------------------------------------------------------------


def with_native(model):
    """``model`` with its single-state kernels compiled as C (irb140_dynamics.native), as
    ``prepare`` makes them (a node at startup, or a program after PROMOTE_AFTER calls).
    Says so when there is no native code (no compiler)."""
    if not prepare(model, timeout=300.0).native:
        print("note: no native kernels (no C compiler, or IRB140_NATIVE=0): the Python forms are timed")
    return model


@contextmanager
def python_form():
    """Calls in this block stay in the kernels' Python form (IRB140_NATIVE=0), on fresh models."""
    before = os.environ.get("IRB140_NATIVE")
    os.environ["IRB140_NATIVE"] = "0"
    try:
        yield
    finally:
        if before is None:
            del os.environ["IRB140_NATIVE"]
        else:
            os.environ["IRB140_NATIVE"] = before


def random_states(model, count: int, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q uniform within the joint limits, qd in +-2 rad/s, qdd in +-5 rad/s^2."""
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    q = rng.uniform(lower, upper, (count, model.n))
    return q, rng.uniform(-2.0, 2.0, q.shape), rng.uniform(-5.0, 5.0, q.shape)


def symmetric_from_upper(M: np.ndarray) -> np.ndarray:
    """Symmetric matrices (..., n, n) from the upper triangles (all that crba guarantees)."""
    return np.triu(M) + np.swapaxes(np.triu(M, 1), -1, -2)


def check_same(label: str, ours, theirs) -> None:
    np.testing.assert_allclose(ours, theirs, **TOLERANCE, err_msg=label)


def single_state(model, pm, data) -> list[Row]:
    """Per-call cost of one state: public functions, raw kernels and the textbook RNEA."""
    q, qd, qdd = (x[0] for x in random_states(model, 1, np.random.default_rng(SEED)))
    lists = q.tolist(), qd.tolist(), qdd.tolist()
    kernels = kernels_of(with_native(model))  # the public functions' rows: native
    textbook = TextbookRnea(model)

    tau = rnea(model, q, qd, qdd)
    check_same("rnea vs pin.rnea", tau, pin.rnea(pm, data, q, qd, qdd))
    check_same("rnea vs textbook", tau, textbook(q, qd, qdd))
    check_same("rnea vs its kernel", tau, kernels.rnea.scalar(*lists))
    check_same("gravity", gravity(model, q), pin.computeGeneralizedGravity(pm, data, q))
    check_same("mass_matrix", mass_matrix(model, q), symmetric_from_upper(pin.crba(pm, data, q)))

    pin_rnea = lambda: pin.rnea(pm, data, q, qd, qdd)  # noqa: E731
    pin_gravity = lambda: pin.computeGeneralizedGravity(pm, data, q)  # noqa: E731
    pin_crba = lambda: pin.crba(pm, data, q)  # noqa: E731
    ours_rnea = lambda: rnea(model, q, qd, qdd)  # noqa: E731
    cases = [  # name, ours, baseline, target
        ("rnea vs pin.rnea", ours_rnea, pin_rnea, Target(0.7)),
        ("rnea kernel, Python form (lists) vs pin.rnea", lambda: kernels.rnea.scalar(*lists), pin_rnea, None),
        ("rnea vs textbook NumPy RNEA", ours_rnea, lambda: textbook(q, qd, qdd), None),
        ("gravity vs computeGeneralizedGravity", lambda: gravity(model, q), pin_gravity, Target(0.7)),
        (
            "gravity kernel, Python form (list) vs computeGeneralizedGravity",
            lambda: kernels.gravity_torques.scalar(lists[0]),
            pin_gravity,
            None,
        ),
        ("mass_matrix vs pin.crba", lambda: mass_matrix(model, q), pin_crba, Target(0.7)),
        (
            "mass_matrix kernel, Python form (list) vs pin.crba",
            lambda: kernels.mass_matrix.scalar(lists[0]),
            pin_crba,
            None,
        ),
    ]
    group = "single state, per call"
    return [
        Row(group, name, Figure.cost(seconds_per_call(ours)), Figure.cost(seconds_per_call(baseline)), target)
        for name, ours, baseline, target in cases
    ]


def batch(model, pm, data) -> list[Row]:
    """States per second of the batch functions and of a Python loop of Pinocchio calls."""
    Q, QD, QDD = random_states(model, BATCH_STATES, np.random.default_rng(SEED + 1))

    def loop(call, shape, count=BATCH_STATES):
        """A Python loop of ``call(i)`` over the first ``count`` states, results stored."""

        def run():
            out = np.empty((count, *shape))
            for i in range(count):
                out[i] = call(i)
            return out

        return run

    vector, matrix = (model.n,), (model.n, model.n)
    unchanged = lambda x: x  # noqa: E731
    cases = [  # name, ours, baseline call on state i, its result shape, for the check, target
        (
            "rnea_batch vs loop of pin.rnea",
            lambda: rnea_batch(model, Q, QD, QDD),
            lambda i: pin.rnea(pm, data, Q[i], QD[i], QDD[i]),
            vector,
            unchanged,
            Target(2, at_least=True),
        ),
        (
            "gravity_batch vs loop of computeGeneralizedGravity",
            lambda: gravity_batch(model, Q),
            lambda i: pin.computeGeneralizedGravity(pm, data, Q[i]),
            vector,
            unchanged,
            None,
        ),
        (
            "mass_matrix_batch vs loop of pin.crba",
            lambda: mass_matrix_batch(model, Q),
            lambda i: pin.crba(pm, data, Q[i]),
            matrix,
            symmetric_from_upper,
            None,
        ),
    ]
    group = f"batch of {BATCH_STATES:,} states"
    rows = []
    for name, ours, call, shape, arrange, target in cases:
        check_same(name, ours()[:BATCH_CHECKED], arrange(loop(call, shape, BATCH_CHECKED)()))
        ours_rate, loop_rate = (
            Figure.rate(seconds_per_call(fn, blocks=BATCH_REPEATS, number=1), BATCH_STATES)
            for fn in (ours, loop(call, shape))
        )
        rows.append(Row(group, name, ours_rate, loop_rate, target))
    return rows


def urdf_arms() -> list[Row]:
    """Per-call cost on the UR5 and the Panda of example-robot-data, as our loader and
    Pinocchio's parser read the same file (Pinocchio's Panda with its fingers locked), and
    on the DH IRB-140 the same way. Ours with the friction the model carries (the Panda's
    URDF damping: inside our native call; pin.rnea has none, so the check takes it out).
    Ours with native kernels (the default where a C compiler is), then in their Python form."""
    rows = []
    arms = {"IRB-140 (DH)": (irb140(), None), **URDF_ARMS, **TREE_ARMS}
    for name, (text, tip) in arms.items():
        model, pm = _paired_models(text, tip)
        data = pm.createData()
        q, qd, qdd = (x[0] for x in random_states(model, 1, np.random.default_rng(SEED + 2)))
        # Pinocchio's joint order (a tree's differs): its state and ours compared through it
        order = [pm.joints[pm.getJointId(name)].idx_v for name in model.joint_names] if tip == "" else None
        pq, pv, pa = (np.array(x) for x in (q, qd, qdd))
        if order is not None:
            for x, ours in zip((pq, pv, pa), (q, qd, qdd)):
                x[order] = ours
        ours_order = slice(None) if order is None else order
        friction = model.friction.torques(qd) if model.friction is not None else 0.0
        check_same(f"{name} rnea", rnea(model, q, qd, qdd) - friction, pin.rnea(pm, data, pq, pv, pa)[ours_order])
        check_same(f"{name} gravity", gravity(model, q), pin.computeGeneralizedGravity(pm, data, pq)[ours_order])
        M = symmetric_from_upper(pin.crba(pm, data, pq))
        check_same(f"{name} mass_matrix", mass_matrix(model, q), M if order is None else M[np.ix_(order, order)])
        label = f"{name}{' (with its friction)' if model.friction is not None else ''}"
        for form in ("native", "Python"):
            ours = with_native(model) if form == "native" else replace(model)  # a fresh model: no kernels yet
            cases = [
                ("rnea vs pin.rnea", lambda m=ours: rnea(m, q, qd, qdd), lambda: pin.rnea(pm, data, pq, pv, pa)),
                (
                    "gravity vs computeGeneralizedGravity",
                    lambda m=ours: gravity(m, q),
                    lambda: pin.computeGeneralizedGravity(pm, data, pq),
                ),
                ("mass_matrix vs pin.crba", lambda m=ours: mass_matrix(m, q), lambda: pin.crba(pm, data, pq)),
            ]
            group = f"arms, ours {form}, alternating blocks (URDF: load_urdf vs buildModelFromXML), per call"
            for case, call, baseline in cases:
                if form == "native":
                    timed = paired_seconds_per_call(call, baseline)
                else:
                    with python_form():
                        timed = paired_seconds_per_call(call, baseline)
                target = Target(NATIVE_TARGET) if form == "native" else None
                rows.append(Row(group, f"{label} {case}", *(Figure.cost(t) for t in timed), target))
    return rows


def derivatives() -> list[Row]:
    """The derivatives section (see derivatives_section) on the IRB-140, the UR5 and the Panda."""
    arms = {"IRB-140 (DH)": (irb140(), None), **URDF_ARMS}
    paired = {name: _paired_models(text, tip) for name, (text, tip) in arms.items()}
    return derivative_rows(paired, paired_seconds_per_call, SEED + 3)


def _paired_models(text, tip):
    """(our model, Pinocchio's) of a URDF's chain to ``tip`` (``""``: its whole tree), or of
    a model."""
    if tip is None:
        return text, pinocchio_model(text)
    if tip == "":
        model = load_urdf(text).model
        pm = pin.buildModelFromXML(text)
        pm.gravity.linear = np.array(model.gravity)
        return model, pm
    loaded = load_urdf(text, tip_link=tip)
    model = loaded.model
    pm = pin.buildModelFromXML(text)
    held = [pm.getJointId(joint) for joint in loaded.held_joints]
    pm = pin.buildReducedModel(pm, held, pin.neutral(pm)) if held else pm
    pm.gravity.linear = np.array(model.gravity)
    return model, pm


def paired_seconds_per_call(ours, baseline, blocks: int = PAIRED_BLOCKS, calls: int = 40):
    """Seconds per call of each in ``blocks`` blocks of ``calls``, the two alternating block
    by block: on a shared machine both then meet the same load (their best blocks compare)."""
    timers = timeit.Timer(ours), timeit.Timer(baseline)
    for timer in timers:
        timer.timeit(calls)  # warm up
    times = ([], [])
    for _ in range(blocks):
        for timer, samples in zip(timers, times):
            samples.append(timer.timeit(calls) / calls)
    return times


def _urdf_paths() -> dict[str, tuple[Path, str]]:
    """name -> (URDF file, tip link) of example-robot-data's UR5 and Panda."""
    arms = {
        "UR5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
        "Panda": ("panda_description/urdf/panda.urdf", "panda_hand"),
    }
    return {name: (example_robot_urdf(path), tip) for name, (path, tip) in arms.items()}


def _baxter() -> str:
    """example-robot-data's Baxter, both arms and the head pan (15 joints): its grippers'
    fingers made fixed joints, in the text both read."""
    text = example_robot_urdf("baxter_description/urdf/baxter.urdf").read_text()
    return re.sub(r'(<joint\s+name="[lr]_gripper_[lr]_finger_joint"\s+type=)"prismatic"', r'\1"fixed"', text)


URDF_PATHS = _urdf_paths()
URDF_ARMS = {name: (path.read_text(), tip) for name, (path, tip) in URDF_PATHS.items()}
TREE_ARMS = {"Baxter (tree, 15 joints)": (_baxter(), "")}  # the whole tree: tip ""


def kernel_generation() -> tuple[list[Row], dict]:
    """Trace-and-compile time of each kernel on fresh models, and the first rnea() call; then
    that of a model that differs only in its payload mass (it shares the compiled code)."""
    payload_changed = "first rnea() call, another payload mass (shared code)"
    times = {name: [] for name in ("kernels setup", *KERNELS, "first rnea() call", payload_changed)}
    for k in range(FRESH_MODELS):
        kernel_cache._arm.cache_clear()  # compiled code is shared between models of the same arm
        kernels = _timed(times["kernels setup"], lambda: kernels_of(irb140()))
        for name in KERNELS:
            _timed(times[name], lambda: getattr(kernels, name))
        kernel_cache._arm.cache_clear()
        fresh = irb140()
        zeros = np.zeros(fresh.n)
        _timed(times["first rnea() call"], lambda: rnea(fresh, zeros, zeros, zeros))
        loaded = irb140(payload=RigidBody(1.0 + k))
        _timed(times[payload_changed], lambda: rnea(loaded, zeros, zeros, zeros))
    group = "kernel generation, fresh model"
    rows = [Row(group, name, Figure.cost(samples, "ms")) for name, samples in times.items()]
    source_lines = {name: getattr(kernels, name).source.count("\n") for name in KERNELS}
    return rows, source_lines


def _timed(samples: list[float], fn):
    start = time.perf_counter()
    result = fn()
    samples.append(time.perf_counter() - start)
    return result


def main() -> None:
    started = time.perf_counter()
    model = irb140()
    pm = pinocchio_model(model)  # the builder the tests check against our core
    data = pm.createData()
    generation, source_lines = kernel_generation()  # first: on fresh models, before any warm-up
    rows = single_state(model, pm, data) + batch(model, pm, data) + generation + preparation(URDF_PATHS) + urdf_arms()
    rows += derivatives()
    print_table(rows, "irb140_dynamics core vs Pinocchio (ratio = ours / baseline)")
    path = write_results(
        "core",
        {
            "benchmark": "core",
            "machine": machine_info(("numpy", "pinocchio")),
            "settings": {
                "batch_states": BATCH_STATES,
                "batch_repeats": BATCH_REPEATS,
                "fresh_models": FRESH_MODELS,
                "seed": SEED,
            },
            "rows": [row.as_dict() for row in rows],
            "kernel_source_lines": source_lines,
            "runtime_s": time.perf_counter() - started,
        },
    )
    print(f"raw figures: {shown(path)} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()

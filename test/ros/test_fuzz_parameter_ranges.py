"""Fuzz of every node's numeric parameters (seeded, bounded; a longer run: bench/fuzz_parameters.py).

Every numeric parameter declares a finite range in its descriptor (what `ros2 param
describe` shows). Values from HOSTILE (inf, nan, 1e308, negatives, integers) and random
values in and around its range are set one at a time: a value outside the range, or not
finite, is refused with a reason naming the parameter, and the value in force stays; a value
inside is accepted (an integer for a double too, as 3.0) unless the node's whole check
refuses it, with a reason. A read-only parameter is refused at run time; at startup a value
outside its range stops the node with one line naming it. After the fuzz sim_node still
publishes finite joint states.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from ..support.fuzz_ranges import NODES, SEED, bounds, candidates, numeric_parameters, try_value
from ..support.ros_harness import running

pytestmark = pytest.mark.ros

CASES = 60  # per node


@pytest.mark.parametrize("name", sorted(NODES))
def test_every_numeric_parameter_has_a_finite_range(name):
    with running(NODES[name]) as harness:
        numeric = numeric_parameters(harness.node)
        assert numeric, f"{name} has no numeric parameters?"
        for parameter, descriptor in numeric.items():
            low, high = bounds(descriptor)
            assert math.isfinite(low) and math.isfinite(high) and low <= high, (parameter, low, high)
            value = harness.node.get_parameter(parameter).value
            assert low <= value <= high, (parameter, value, low, high)


@pytest.mark.parametrize("name", sorted(NODES))
def test_fuzz_numeric_parameters(name):
    rng = np.random.default_rng(SEED)
    with running(NODES[name]) as harness:
        node = harness.node
        numeric = numeric_parameters(node)
        names = sorted(numeric)
        for _ in range(CASES):
            parameter = names[rng.integers(len(names))]
            values = candidates(rng, numeric[parameter])
            problem = try_value(node, parameter, numeric[parameter], values[rng.integers(len(values))])
            assert problem is None, problem
        harness.settle()  # the changes accepted are built and in force
        assert getattr(getattr(node, "parameters", None), "failure", None) is None
        if name == "sim_node":
            states = harness.listen(JointState, "joint_states", 100)
            assert harness.spin_until(lambda: len(states) >= 5)
            for state in states:
                assert np.isfinite(state.position).all() and np.isfinite(state.effort).all()


@pytest.mark.parametrize("name", sorted(NODES))
def test_read_only_numeric_parameters_refuse_bad_values_at_startup(name):
    with running(NODES[name]) as harness:
        read_only = {p: d for p, d in numeric_parameters(harness.node).items() if d.read_only}
    for parameter, descriptor in sorted(read_only.items()):
        low, high = bounds(descriptor)
        for value in (math.inf, math.nan, high * 10 + 1 if descriptor.type == 3 else int(high) + 1):
            kind = Parameter.Type.INTEGER if descriptor.type == 2 and not isinstance(value, float) else None
            override = Parameter(parameter, kind or Parameter.Type.DOUBLE, value)
            with (
                pytest.raises(ValueError, match=parameter.replace(".", r"\.")),
                running(NODES[name], parameter_overrides=[override]),
            ):
                pass

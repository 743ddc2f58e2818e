"""Starting payload_check_node as its own process: the defaults, and one clear line for a bad value."""

import pytest

from ..support.node_process import module_command, run_to_exit, run_until_ready
from ..support.paths import CONFIG

PAYLOAD_CHECK_NODE = "irb140_dynamics.nodes.payload_check_node.node"


def test_starts_with_the_defaults_and_stops_cleanly_on_ctrl_c():
    code, output = run_until_ready(module_command(PAYLOAD_CHECK_NODE))
    assert "ready: ~/check for a 0.0 kg payload" in output, output
    assert str(CONFIG) in output
    assert "Traceback" not in output
    assert code == 0, output


@pytest.mark.parametrize(
    "args, field",
    [
        (["-p", "payload.mass:=-1.0"], "payload.mass"),
        (["-p", "payload.mass:=1e200"], "payload.mass: must be between 0 and 1e+06, got 1e+200"),
        (["-p", "payload.com:=[1e200, 0.0, 0.0]"], "payload.com: |com| must be <= 1000 m"),
        (["-p", "rated_payload.com:=[0.0, 0.0]"], "rated_payload.com"),
        (["-p", "payload.inertia:=[1.0, 1.0, 3.0, 0.0, 0.0, 0.0]"], "payload.inertia"),
        (["-p", "diagnostics.warn_use:=-5.0"], "diagnostics.warn_use"),
    ],
)
def test_a_bad_parameter_stops_startup_with_one_clear_line(args, field):
    code, output = run_to_exit(module_command(PAYLOAD_CHECK_NODE, *args))
    assert code == 1, output
    assert "Traceback" not in output
    fatal = [line for line in output.splitlines() if "cannot start" in line]
    assert len(fatal) == 1 and field in fatal[0], output

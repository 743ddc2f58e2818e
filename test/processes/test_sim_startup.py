"""Starting sim_node as `ros2 run` does: ready and a clean stop on Ctrl-C, or one clear line."""

from ..support.node_process import module_command, one_fatal_line, run_to_exit, run_until_ready

SIM_NODE = "irb140_dynamics.nodes.sim_node.node"


def test_starts_with_the_default_model_and_stops_cleanly_on_ctrl_c():
    code, output = run_until_ready(module_command(SIM_NODE))
    assert "ready: 6 joints" in output and "1000 Hz" in output, output
    assert code == 0, output
    assert "Traceback" not in output and "step failed" not in output, output


def test_a_bad_initial_pose_stops_startup_with_one_clear_line():
    pose = "initial_positions:=[0.0, -3.0, 0.0, 0.0, 0.0, 0.0]"
    fatal = one_fatal_line(*run_to_exit(module_command(SIM_NODE, "-p", pose)))
    assert "cannot start" in fatal and "initial_positions: joint_2 at -3.0 rad is outside" in fatal, fatal


def test_a_queue_depth_beyond_its_range_stops_startup_with_one_clear_line():
    fatal = one_fatal_line(*run_to_exit(module_command(SIM_NODE, "-p", "qos.depth:=2000000000")))
    assert "cannot start" in fatal and "qos.depth" in fatal, fatal

#!/usr/bin/env bash
# The run command: sets up .venv (ROS 2 Jazzy wheels, NumPy, colcon), builds the package
# with colcon into ./install (the layout ros2 run uses), and starts id_node and
# payload_check_node with the default IRB-140 model.
#
#   ./scripts/run.sh                  the two nodes
#   ./scripts/run.sh --demo           the closed loop: a simulated arm (sim_node, a 'true' IRB-140
#                                     that differs from the model: config/true_arm.yaml), id_node
#                                     in computed-torque mode on the report's model, and demo_node
#                                     sending a reference motion and printing the tracking error;
#                                     a plot demo_tracking.png at the end (Ctrl-C)
#   ./scripts/run.sh [--demo] ARGS    ARGS go to id_node and payload_check_node after --ros-args,
#                                     e.g. --params-file my_robot.yaml -p payload.mass:=2.0
set -euo pipefail
cd "$(dirname "$0")/.."
demo=false
if [ "${1:-}" = "--demo" ]; then demo=true; shift; fi
source scripts/env.sh run
colcon --log-base build/log build --paths . --build-base build --install-base install >build.log 2>&1 \
    || { cat build.log >&2; exit 1; }
set +u  # colcon's setup scripts read unset variables
# shellcheck disable=SC1091
source install/setup.bash
set -u
ros_args=()
if [ $# -gt 0 ]; then ros_args=(--ros-args "$@"); fi
bin=install/irb140_dynamics/lib/irb140_dynamics
share=install/irb140_dynamics/share/irb140_dynamics
trap 'kill -INT $(jobs -p) 2>/dev/null; wait' INT TERM EXIT
if $demo; then
    "$bin/sim_node" --ros-args --params-file "$share/config/true_arm.yaml" \
        -p initial_positions:="[0.0, -0.6, 1.0, 0.0, 0.5, 0.0]" -p reset_hold:=1.0 &
    id_args=(--ros-args -p effort_commands.enabled:=true -p effort_commands.source:=computed_torque "$@")
else
    id_args=("${ros_args[@]}")
fi
"$bin/id_node" "${id_args[@]}" &
"$bin/payload_check_node" "${ros_args[@]}" &
if $demo; then "$bin/demo_node" & fi
wait -n

